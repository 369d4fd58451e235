"""Trajectories for `moslam eval`: damaged ground truth and estimates in TUM and KITTI format (bad
fields, NaN stamps, out-of-order and duplicate stamps, zero quaternions, too few poses), KITTI
times files, and run manifests of `eval table`."""

import os
import random

from helpers import Spec, any_line_of, clone, damaged_line_names, read_lines, write_lines
from mutate import byte_mutations, line_mutations, read_bytes, replace_file

# The base sequences are a fraction of a second long: RPE over pairs 1 frame apart.
EXTRA = {"ate": [], "rpe": ["--delta", "1", "--delta-unit", "f"]}


def pair_specs(rng, tag, gt, est, commands, extra=(), max_fields=4):
    """Line mutations of the estimate and of the ground truth, each through every command."""
    specs = []
    for which in ("est", "gt"):
        src = est if which == "est" else gt
        lines = read_lines(src)
        for name, mutated, pick in line_mutations(rng, lines, " ", max_fields):
            if tag == "kitti" and name == "duplicate_line":
                pick = None  # KITTI rows have no stamps: a repeated row is one pose too many
            for command in commands:
                def build(d, mutated=mutated, pick=pick, which=which, command=command):
                    g = clone(gt, os.path.join(d, "gt.txt"))
                    e = clone(est, os.path.join(d, "est.txt"))
                    path = e if which == "est" else g
                    write_lines(path, mutated)
                    return (["eval", command, g, e] + EXTRA[command] + list(extra),
                            damaged_line_names(path, lines, pick))
                specs.append(Spec("eval", f"{tag}_{command}_{which}_{name}", build))
    return specs


def quaternion_specs(gt, est):
    """TUM rows whose rotation is no rotation: zero, tiny, huge or non-unit quaternions."""
    specs = []
    for name, q in [("zero", "0 0 0 0"), ("tiny", "1e-300 0 0 1e-300"), ("huge", "1e300 0 0 1"),
                    ("unnormalised", "0 0 0 2"), ("negative_w", "0 0 0 -1")]:
        def build(d, q=q):
            g = clone(gt, os.path.join(d, "gt.txt"))
            e = clone(est, os.path.join(d, "est.txt"))
            lines = read_lines(est)
            lines[2] = " ".join(lines[2].split()[:4]) + " " + q
            write_lines(e, lines)
            return ["eval", "ate", g, e], [[e], any_line_of(e)]
        specs.append(Spec("eval", f"quaternion_{name}", build))
    return specs


def kitti_specs(rng, kitti):
    """KITTI poses against themselves, by index and with a times file."""
    poses = os.path.join(kitti, "poses.txt")
    times = os.path.join(kitti, "times.txt")
    specs = pair_specs(rng, "kitti", poses, poses, ["ate"], max_fields=5)
    for rows in (1, 2, 150):
        def build(d, rows=rows):
            g = clone(poses, os.path.join(d, "gt.txt"))
            e = os.path.join(d, "est.txt")
            lines = [line for line in read_lines(poses) if line.strip()]
            write_lines(e, (lines * 40)[:rows])
            return ["eval", "ate", g, e], [[e, g]]
        specs.append(Spec("eval", f"kitti_index_{rows}_rows", build))
    for name, mutated, _ in line_mutations(rng, read_lines(times), " "):
        def build(d, mutated=mutated):
            g = clone(poses, os.path.join(d, "gt.txt"))
            t = os.path.join(d, "times.txt")
            write_lines(t, mutated)
            est = os.path.join(d, "est.txt")
            write_lines(est, [f"{0.1 * i:.6f} 0 0 {i} 0 0 0 1" for i in range(5)])
            return ["eval", "ate", g, est, "--gt-times", t], [[t, g]]
        specs.append(Spec("eval", f"kitti_times_{name}", build))
    return specs


def manifest_specs(gt, est):
    rows = {
        "valid": None,
        "empty": "",
        "header_only": "sequence,method,gt,est\n",
        "missing_column": "sequence,method,gt,est\nseq,a,{gt}\n",
        "extra_column": "sequence,method,gt,est\nseq,a,{gt},{est},x,y\n",
        "no_file": "sequence,method,gt,est\nseq,a,{gt},{d}/none.txt\n",
        "quoted": "sequence,method,gt,est\n\"seq,a\",a,{gt},{est}\n",
        "binary": "\x00\x01\x02",
        "duplicate_run": "sequence,method,gt,est\nseq,a,{gt},{est}\nseq,a,{gt},{est}\n",
    }
    specs = []
    for name, text in rows.items():
        def build(d, text=text):
            g = clone(gt, os.path.join(d, "gt.txt"))
            e = clone(est, os.path.join(d, "est.txt"))
            m = os.path.join(d, "runs.csv")
            body = text if text is not None else "sequence,method,gt,est\nseq,a,{gt},{est}\n"
            replace_file(m, body.format(gt=g, est=e, d=d))
            return ["eval", "table", "--manifest", m] + EXTRA["rpe"], [[m]]
        specs.append(Spec("eval", f"manifest_{name}", build, valid=text is None))
    return specs


def byte_specs(rng, gt, est):
    specs = []
    for name, data in byte_mutations(rng, read_bytes(est)):
        def build(d, data=data):
            g = clone(gt, os.path.join(d, "gt.txt"))
            e = os.path.join(d, "est.txt")
            replace_file(e, data)
            return ["eval", "rpe", g, e] + EXTRA["rpe"], [[e]]
        specs.append(Spec("eval", f"est_bytes_{name}", build))

    for command in ("ate", "rpe"):
        def valid(d, command=command):
            g = clone(gt, os.path.join(d, "gt.txt"))
            e = clone(est, os.path.join(d, "est.txt"))
            return ["eval", command, g, e] + EXTRA[command], []
        specs.append(Spec("eval", f"valid_{command}", valid, valid=True))
    return specs


def specs(inputs, seed):
    rng = random.Random(seed + 2)
    gt = os.path.join(inputs["tum"], "groundtruth.txt")
    est = inputs["estimate"]
    return (pair_specs(rng, "tum", gt, est, ["ate", "rpe"]) + quaternion_specs(gt, est) +
            kitti_specs(rng, inputs["kitti"]) + manifest_specs(gt, est) + byte_specs(rng, gt, est))
