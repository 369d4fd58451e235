"""The small valid inputs every case starts from, written by moslam itself (`moslam synth`) or
derived from its output here: TUM RGB-D and KITTI sequences, an EuRoC sequence and an image folder
made of the KITTI images, trajectories, mask folders, a vocabulary and a model card."""

import os
import random
import shutil
import subprocess

import cv2
import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def synth(moslam, preset, frames, width, height, out):
    if os.path.isfile(os.path.join(out, "settings.yaml")):
        return
    env = dict(os.environ, OMP_WAIT_POLICY="passive")
    subprocess.run([moslam, "synth", "--preset", preset, "--seed", "1", "--frames", str(frames),
                    "--width", str(width), "--height", str(height), "--out", out],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)


def make_euroc(kitti, out):
    """mav0/cam0 and cam1 (data.csv + data/<ns>.png) from the KITTI images."""
    if os.path.isdir(out):
        return
    names = sorted(os.listdir(os.path.join(kitti, "image_0")))
    for cam, folder in (("cam0", "image_0"), ("cam1", "image_1")):
        data = os.path.join(out, "mav0", cam, "data")
        os.makedirs(data)
        rows = ["#timestamp [ns],filename"]
        for i, name in enumerate(names):
            stamp = 1403636579763555584 + i * 50000000
            shutil.copy(os.path.join(kitti, folder, name), os.path.join(data, f"{stamp}.png"))
            rows.append(f"{stamp},{stamp}.png")
        with open(os.path.join(out, "mav0", cam, "data.csv"), "w") as f:
            f.write("\n".join(rows) + "\n")


def make_folder(kitti, out):
    if os.path.isdir(out):
        return
    os.makedirs(out)
    for name in sorted(os.listdir(os.path.join(kitti, "image_0"))):
        shutil.copy(os.path.join(kitti, "image_0", name), os.path.join(out, name))


def make_masks(tum, out):
    """DIR/<stem>.png, 255 = movable, from the generator's class images."""
    if os.path.isdir(out):
        return
    os.makedirs(out)
    for name in sorted(os.listdir(os.path.join(tum, "class"))):
        labels = cv2.imread(os.path.join(tum, "class", name), cv2.IMREAD_UNCHANGED)
        cv2.imwrite(os.path.join(out, name), np.where(labels > 0, 255, 0).astype(np.uint8))


def make_vocabulary(moslam, out_dir):
    """A DBoW2 text vocabulary, k = 3, L = 2 (12 nodes), and its binary form."""
    text = os.path.join(out_dir, "small.txt")
    binary = os.path.join(out_dir, "small.mvoc")
    if os.path.isfile(binary):
        return text, binary
    rng = random.Random(7)
    lines = ["3 2 0 0"]
    for parent, leaf in [(0, 0)] * 3 + [(1, 1)] * 3 + [(2, 1)] * 3 + [(3, 1)] * 3:
        desc = " ".join(str(rng.randrange(256)) for _ in range(32))
        weight = 0.0 if not leaf else round(rng.uniform(0.1, 2.0), 6)
        lines.append(f"{parent} {leaf} {desc} {weight}")
    os.makedirs(out_dir, exist_ok=True)
    with open(text, "w") as f:
        f.write("\n".join(lines) + "\n")
    subprocess.run([moslam, "vocab", "convert", text, binary], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   env=dict(os.environ, OMP_WAIT_POLICY="passive"))
    return text, binary


def make_estimate(gt, out, seed):
    """The ground truth with a little noise: a valid estimate for `moslam eval`."""
    rng = random.Random(seed)
    rows = []
    with open(gt) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = line.split()
            for k in (1, 2, 3):
                v[k] = f"{float(v[k]) + rng.gauss(0, 0.01):.6f}"
            rows.append(" ".join(v))
    with open(out, "w") as f:
        f.write("\n".join(rows) + "\n")


def make_map(moslam, tum, vocabulary, out_dir):
    """A map file (`moslam run --save-map`) of the TUM sequence, with the small vocabulary."""
    path = os.path.join(out_dir, "w_xyz.map")
    if os.path.isfile(path):
        return path
    os.makedirs(out_dir, exist_ok=True)
    subprocess.run([moslam, "run", "--dataset", "tum", tum, "--settings",
                    os.path.join(tum, "settings.yaml"), "--vocabulary", vocabulary,
                    "--deterministic", "--quiet", "--out", os.path.join(out_dir, "run"),
                    "--save-map", path], check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL, env=dict(os.environ, OMP_WAIT_POLICY="passive"))
    return path


def make_base_inputs(moslam, base):
    """Paths of the base inputs (a dict); made once per work folder and reused. The marker file
    is written last, so that inputs an interrupted run left half made are made again."""
    marker = os.path.join(base, "complete")
    if not os.path.isfile(marker) and os.path.isdir(base):
        shutil.rmtree(base)
    os.makedirs(base, exist_ok=True)
    tum = os.path.join(base, "tum")
    kitti = os.path.join(base, "kitti")
    synth(moslam, "w_xyz", 8, 320, 240, tum)
    synth(moslam, "kitti_cars", 5, 320, 128, kitti)
    make_euroc(kitti, os.path.join(base, "euroc"))
    make_folder(kitti, os.path.join(base, "folder"))
    make_masks(tum, os.path.join(base, "masks"))
    vocab_text, vocab_binary = make_vocabulary(moslam, os.path.join(base, "vocab"))
    estimate = os.path.join(base, "estimate.txt")
    make_estimate(os.path.join(tum, "groundtruth.txt"), estimate, 3)
    map_file = make_map(moslam, tum, vocab_binary, os.path.join(base, "map"))
    open(marker, "w").close()
    shared = os.environ.get("MOSLAM_SHARED", os.path.join(os.path.dirname(REPO), "shared"))
    return {
        "repo": REPO, "base": base, "tum": tum, "kitti": kitti,
        "euroc": os.path.join(base, "euroc"), "folder": os.path.join(base, "folder"),
        "masks": os.path.join(base, "masks"), "vocab_text": vocab_text,
        "vocab_binary": vocab_binary, "estimate": estimate, "map": map_file,
        "shared": shared if os.path.isdir(os.path.join(shared, "models")) else None,
    }
