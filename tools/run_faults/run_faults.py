#!/usr/bin/env python3
"""Faults in the middle of `moslam run` (issue 31), through the real binary: SIGINT and SIGTERM
while it tracks, a mask file and an image that break at frame k, an output folder that cannot be
written, a disk that fills up (the file-size limit, as `ulimit -f` sets it). Each must end with a
non-zero exit status and a message naming what failed, every output it leaves complete (no file
cut short, no temporary file), and summary.json saying how the run ended.

    /usr/bin/python3 tools/run_faults/run_faults.py --moslam build/apps/moslam/moslam [--work DIR]

Exit 0: every case as expected; 1: a case failed (each says why); 77: skipped (no OpenCV/NumPy).
The sequence is a 90-frame synthetic w_xyz at 320x240 made by `moslam synth` (a few seconds)."""

import argparse
import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import time

try:
    import cv2  # noqa: F401  (base.make_masks needs it)
    import numpy as np  # noqa: F401
except ImportError:
    print("run_faults: skipped: Debian's python3-opencv and python3-numpy are needed "
          "(run with /usr/bin/python3)")
    sys.exit(77)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                "bad_input_corpus"))
import base  # noqa: E402

FRAMES = 90
ENV = dict(os.environ, OMP_WAIT_POLICY="passive")


class Failure(Exception):
    pass


def expect(condition, message):
    if not condition:
        raise Failure(message)


def run_command(moslam, tum, out, extra, quiet=True):
    """`--quiet` keeps the log at warnings: the signal cases leave it out to read the debug log."""
    return [moslam, "--log-level", "debug", "run", "--dataset", "tum", tum, "--settings",
            os.path.join(tum, "settings.yaml"), "--vocabulary", "none", "--out", out] + (
                ["--quiet"] if quiet else []) + extra


def check_outputs(out, status, frames=None):
    """The outputs in `out` are whole; summary.json says `status`; returns its frame count."""
    names = os.listdir(out)
    expect(not [n for n in names if ".tmp" in n], f"temporary files left in {out}: {names}")
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    expect(summary["end"]["status"] == status,
           f"summary.json says {summary['end']}, expected status {status}")
    tracked = summary["frames"]
    if frames is not None:
        expect(tracked == frames, f"summary.json counts {tracked} frames, expected {frames}")
    with open(os.path.join(out, "frames.csv")) as f:
        rows = f.read().splitlines()
    expect(len(rows) == tracked + 1, f"frames.csv has {len(rows) - 1} rows for {tracked} frames")
    expect(all(r.count(",") == rows[0].count(",") for r in rows), "a frames.csv row is cut short")
    with open(os.path.join(out, "CameraTrajectory.txt")) as f:
        poses = f.read().splitlines()
    expect(all(len(p.split()) == 8 for p in poses), "a trajectory line is cut short")
    expect(len(poses) <= tracked, f"{len(poses)} poses for {tracked} frames")
    return summary


def case_signal(moslam, data, work, sig, code):
    """The signal arrives once frame 5 has been tracked (the debug log says so), in a run paced
    at the data's 30 frames/s, so that most of it is still ahead."""
    out = os.path.join(work, f"out_{sig.name}")
    proc = subprocess.Popen(run_command(moslam, data["tum"], out, ["--realtime"], quiet=False),
                            env=ENV,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    sent = False
    for line in proc.stderr:
        if "frame 5 (" in line:
            proc.send_signal(sig)
            sent = True
            break
    expect(sent, "the debug log never reported frame 5")
    stdout, stderr = proc.communicate(timeout=120)
    expect(proc.returncode == code, f"exit status {proc.returncode}, expected {code}: {stderr[-800:]}")
    summary = check_outputs(out, "interrupted")
    expect(f"interrupted by {sig.name}" in summary["end"]["message"], summary["end"]["message"])
    expect(6 <= summary["frames"] < FRAMES, f"{summary['frames']} frames tracked")
    expect(f"interrupted by {sig.name}" in stdout, "the printed summary does not say why it ended")


def case_broken_mask(moslam, data, work):
    masks = os.path.join(work, "masks")
    shutil.rmtree(masks, ignore_errors=True)
    shutil.copytree(data["masks"], masks)
    broken = os.path.join(masks, sorted(os.listdir(masks))[20])
    with open(broken, "wb") as f:
        f.write(b"not a PNG image")
    out = os.path.join(work, "out_mask")
    proc = subprocess.run(run_command(moslam, data["tum"], out, ["--mask-source", "files", masks,
                                                                  "--deterministic"]),
                          env=ENV, capture_output=True, text=True, timeout=300)
    expect(proc.returncode == 2, f"exit status {proc.returncode}, expected 2")
    expect(broken in proc.stderr, f"the error does not name {broken}: {proc.stderr[-800:]}")
    summary = check_outputs(out, "failed", frames=20)
    expect(broken in summary["end"]["message"], summary["end"]["message"])


def case_broken_image(moslam, data, work):
    tum = os.path.join(work, "tum_broken")
    shutil.rmtree(tum, ignore_errors=True)
    shutil.copytree(data["tum"], tum)
    broken = os.path.join(tum, "rgb", sorted(os.listdir(os.path.join(tum, "rgb")))[15])
    with open(broken, "wb") as f:
        f.write(b"\x89PNG cut short")
    out = os.path.join(work, "out_image")
    proc = subprocess.run(run_command(moslam, tum, out, ["--deterministic"]), env=ENV,
                          capture_output=True, text=True, timeout=300)
    expect(proc.returncode == 2, f"exit status {proc.returncode}, expected 2")
    expect(broken in proc.stderr, f"the error does not name {broken}: {proc.stderr[-800:]}")
    check_outputs(out, "failed", frames=15)


def case_unwritable_folder(moslam, data, work):
    blocker = os.path.join(work, "a_file")
    with open(blocker, "w") as f:
        f.write("x")
    out = os.path.join(blocker, "out")
    start = time.monotonic()
    proc = subprocess.run(run_command(moslam, data["tum"], out, []), env=ENV,
                          capture_output=True, text=True, timeout=120)
    expect(proc.returncode == 2, f"exit status {proc.returncode}, expected 2")
    expect(out in proc.stderr and "cannot be created" in proc.stderr, proc.stderr[-800:])
    expect("frame 0 (" not in proc.stderr, "the run started before the folder was checked")
    print(f"  (refused after {time.monotonic() - start:.1f} s)")


def case_disk_full(moslam, data, work):
    """A file-size limit of 4 KB: the per-frame log of 90 frames (about 11 KB) cannot be written."""
    out = os.path.join(work, "out_full")
    limit = 4096

    def small_files():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))

    proc = subprocess.run(run_command(moslam, data["tum"], out, ["--deterministic"]), env=ENV,
                          capture_output=True, text=True, timeout=300, preexec_fn=small_files)
    expect(proc.returncode == 2, f"exit status {proc.returncode}, expected 2: {proc.stderr[-800:]}")
    expect("File too large" in proc.stderr and "frames.csv" in proc.stderr, proc.stderr[-800:])
    names = os.listdir(out)
    expect(not [n for n in names if ".tmp" in n], f"temporary files left: {names}")
    expect("frames.csv" not in names, "frames.csv was left cut short")
    for name in names:
        expect(os.path.getsize(os.path.join(out, name)) <= limit, f"{name} is over the limit")
    if "summary.json" in names:
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
        expect(any("frames.csv" in e for e in summary["output_errors"]),
               "summary.json does not list frames.csv among the outputs not written")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moslam", required=True)
    parser.add_argument("--work", default="out/run_faults")
    args = parser.parse_args()
    moslam = os.path.abspath(args.moslam)
    work = os.path.abspath(args.work)
    os.makedirs(work, exist_ok=True)
    tum = os.path.join(work, "tum")
    base.synth(moslam, "w_xyz", FRAMES, 320, 240, tum)
    base.make_masks(tum, os.path.join(work, "masks_base"))
    data = {"tum": tum, "masks": os.path.join(work, "masks_base")}
    cases = [
        ("SIGINT while tracking", lambda: case_signal(moslam, data, work, signal.SIGINT, 130)),
        ("SIGTERM while tracking", lambda: case_signal(moslam, data, work, signal.SIGTERM, 143)),
        ("a mask file broken at frame 20", lambda: case_broken_mask(moslam, data, work)),
        ("an image broken at frame 15", lambda: case_broken_image(moslam, data, work)),
        ("an output folder that cannot be made", lambda: case_unwritable_folder(moslam, data, work)),
        ("a disk that fills up (4 KB file limit)", lambda: case_disk_full(moslam, data, work)),
    ]
    failed = 0
    for name, case in cases:
        start = time.monotonic()
        try:
            case()
            print(f"ok     {name} ({time.monotonic() - start:.1f} s)")
        except (Failure, subprocess.TimeoutExpired, OSError, KeyError, ValueError) as e:
            failed += 1
            print(f"FAILED {name}: {e}")
    print(f"run_faults: {len(cases) - failed} of {len(cases)} cases as expected")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
