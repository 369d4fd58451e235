#!/usr/bin/env python3
"""`moslam run --deterministic` gives the same trajectories byte for byte (issue 31): run again,
and with other thread counts for the parts that have threads of their own: libtorch's intra-op
threads (the model card's `threads`), the CRF's (`crf.num_threads`), OpenMP's (OMP_NUM_THREADS)
and OpenBLAS's (OPENBLAS_NUM_THREADS). The weak person network and the depth CRF make the masks,
so every threaded part of the pipeline is in the loop. libtorch's results depend on its thread
count (the person network's mask differed by a pixel between 1 and 2 threads on an AMD EPYC with
AVX2, 2026-12-07), so --deterministic runs the network on one thread whatever the card says; the
variants with the card at 2 threads check that it does.

    /usr/bin/python3 tools/determinism/determinism.py --moslam build/apps/moslam/moslam [--work DIR]

Compared: CameraTrajectory.txt and KeyFrameTrajectory.txt byte for byte, and frames.csv with its
time and memory columns left out (states, feature, match and inlier counts, keyframes, mask
fractions, map sizes).
Exit 0: all identical; 1: a difference (the first differing line is printed); 77: skipped."""

import argparse
import csv
import io
import os
import subprocess
import sys

try:
    import cv2  # noqa: F401  (base.synth's helpers import it)
except ImportError:
    print("determinism: skipped: Debian's python3-opencv is needed (run with /usr/bin/python3)")
    sys.exit(77)

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(HERE, "..", "bad_input_corpus"))
import base  # noqa: E402

CARD = os.path.join(REPO, "configs", "models", "weak_synth_person.yaml")
MODEL = os.path.join(REPO, "data", "models", "weak_synth_person.mnet")
FRAMES = 40


def card_with_threads(work, torch_threads, crf_threads):
    """The shipped card with other thread counts (and the model by its absolute path)."""
    with open(CARD) as f:
        lines = f.read().splitlines()
    out = []
    for line in lines:
        if line.startswith("threads:"):
            line = f"threads: {torch_threads}"
        elif line.startswith("model:"):
            line = f"model: {MODEL}"
        elif line.strip().startswith("num_threads:"):
            line = f"  num_threads: {crf_threads}"
        out.append(line)
    path = os.path.join(work, f"card_t{torch_threads}_c{crf_threads}.yaml")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    return path


def run(moslam, tum, card, out, env_extra):
    env = dict(os.environ, OMP_WAIT_POLICY="passive", **env_extra)
    proc = subprocess.run([moslam, "run", "--dataset", "tum", tum, "--settings",
                           os.path.join(tum, "settings.yaml"), "--vocabulary", "none",
                           "--mask-source", "model", "--model-card", card, "--crf", "d",
                           "--deterministic", "--quiet", "--out", out],
                          env=env, capture_output=True, text=True, timeout=600)
    if proc.returncode != 0:
        raise RuntimeError(f"moslam run failed ({proc.returncode}): {proc.stderr[-1500:]}")


def untimed_frames(path):
    """frames.csv without its time and memory columns (`*_ms`, `rss_mb`: the machine's, not the
    run's), as text."""
    with open(path) as f:
        rows = list(csv.reader(f))
    keep = [i for i, name in enumerate(rows[0]) if not name.endswith("_ms") and name != "rss_mb"]
    text = io.StringIO()
    csv.writer(text).writerows([[row[i] for i in keep] for row in rows])
    return text.getvalue()


def first_difference(a, b):
    for number, (x, y) in enumerate(zip(a.splitlines(), b.splitlines()), 1):
        if x != y:
            return f"line {number}:\n    {x}\n    {y}"
    return f"lengths differ: {len(a.splitlines())} and {len(b.splitlines())} lines"


def outputs(out):
    with open(os.path.join(out, "CameraTrajectory.txt")) as f:
        camera = f.read()
    with open(os.path.join(out, "KeyFrameTrajectory.txt")) as f:
        keyframes = f.read()
    return {"CameraTrajectory.txt": camera, "KeyFrameTrajectory.txt": keyframes,
            "frames.csv (untimed)": untimed_frames(os.path.join(out, "frames.csv"))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moslam", required=True)
    parser.add_argument("--work", default="out/determinism")
    args = parser.parse_args()
    moslam = os.path.abspath(args.moslam)
    work = os.path.abspath(args.work)
    os.makedirs(work, exist_ok=True)
    tum = os.path.join(work, "tum")
    base.synth(moslam, "w_xyz", FRAMES, 320, 240, tum)
    one = card_with_threads(work, 1, 1)
    two = card_with_threads(work, 2, 2)
    variants = [
        ("reference: card threads 1, CRF threads 1", one, {}),
        ("the same again", one, {}),
        ("card threads 2, CRF threads 2", two, {}),
        ("card threads 2, CRF threads 2, OMP_NUM_THREADS=1, OPENBLAS_NUM_THREADS=1", two,
         {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}),
        ("card threads 1, CRF threads 1, OMP_NUM_THREADS=2, OPENBLAS_NUM_THREADS=2", one,
         {"OMP_NUM_THREADS": "2", "OPENBLAS_NUM_THREADS": "2"}),
    ]
    reference = None
    failed = 0
    for k, (name, card, env) in enumerate(variants):
        out = os.path.join(work, f"run{k}")
        run(moslam, tum, card, out, env)
        result = outputs(out)
        if reference is None:
            reference = result
            poses = len(result["CameraTrajectory.txt"].splitlines())
            print(f"ok     {name}: {poses} poses")
            if poses < FRAMES // 2:
                print(f"FAILED the reference run tracked only {poses} of {FRAMES} frames")
                return 1
            continue
        diffs = [f for f in reference if result[f] != reference[f]]
        if diffs:
            failed += 1
            print(f"FAILED {name}: {', '.join(diffs)} differ; "
                  f"{diffs[0]} {first_difference(reference[diffs[0]], result[diffs[0]])}")
        else:
            print(f"ok     {name}: identical")
    print(f"determinism: {len(variants) - 1 - failed} of {len(variants) - 1} variants identical")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
