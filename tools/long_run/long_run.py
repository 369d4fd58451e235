#!/usr/bin/python3
"""A long run's memory and map over time (issue 31, docs/ROBUSTNESS.md "Long runs").

  long_run.py run --moslam build/apps/moslam/moslam --work DIR [--frames 10000] [--seed 4]
      renders the loop_room preset (a 1 m circle, one lap every 240 frames) for --frames frames
      into DIR/loop_room_<seed> unless it is there, runs `moslam run` on it with every thread on
      (DIR/run_<seed>), then plots as below
  long_run.py self-test
      plots a made-up frames.csv (memory rising, then flat) and checks the picture and the
      plateau figures (ctest tools/long_run_selftest)
  long_run.py plot FRAMES_CSV OUT.png [--title T]
      draws resident memory (MiB), map keyframes and map points against the frame index from a
      run's frames.csv (columns rss_mb, map_keyframes, map_points) and prints the plateau

The plateau: the mean of each quantity over each tenth of the run, and the growth from the
second half's first tenth to its last, so that "levels off" is a number and not a reading of
the picture. Needs Debian's python3-numpy and python3-opencv (/usr/bin/python3).
"""
import argparse
import csv
import os
import subprocess
import sys

try:
    import cv2
    import numpy as np
except ImportError:
    print("long_run: skipped: Debian's python3-numpy and python3-opencv are needed "
          "(run with /usr/bin/python3)")
    sys.exit(77)


def read_columns(path, names):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{path}: no frame rows")
    missing = [n for n in names + ["index"] if n not in rows[0]]
    if missing:
        sys.exit(f"{path}: no column {', '.join(missing)} (a frames.csv of moslam run)")
    index = np.array([int(r["index"]) for r in rows])
    return index, {n: np.array([float(r[n]) for r in rows]) for n in names}


def nice_ticks(lo, hi, count=5):
    span = max(hi - lo, 1e-9)
    raw = span / count
    magnitude = 10 ** np.floor(np.log10(raw))
    step = min((m * magnitude for m in (1, 2, 5, 10) if m * magnitude >= raw), default=raw)
    start = np.ceil(lo / step) * step
    return [start + k * step for k in range(int((hi - start) / step) + 1)]


def draw_panel(img, box, x, y, label, colour):
    """One line chart in box = (left, top, width, height) with axes, ticks and its label."""
    left, top, width, height = box
    black, grey = (0, 0, 0), (200, 200, 200)
    x0, x1 = float(x.min()), float(x.max())
    y0, y1 = 0.0, float(y.max()) * 1.1 if y.max() > 0 else 1.0
    px = lambda v: int(left + (v - x0) / max(x1 - x0, 1e-9) * width)
    py = lambda v: int(top + height - (v - y0) / max(y1 - y0, 1e-9) * height)
    font = cv2.FONT_HERSHEY_SIMPLEX
    for t in nice_ticks(y0, y1):
        cv2.line(img, (left, py(t)), (left + width, py(t)), grey, 1)
        text = f"{t:g}"
        cv2.putText(img, text, (left - 8 - 9 * len(text), py(t) + 5), font, 0.45, black, 1,
                    cv2.LINE_AA)
    for t in nice_ticks(x0, x1, 10):
        cv2.line(img, (px(t), top + height), (px(t), top + height + 5), black, 1)
        cv2.putText(img, f"{t:g}", (px(t) - 15, top + height + 20), font, 0.45, black, 1,
                    cv2.LINE_AA)
    cv2.rectangle(img, (left, top), (left + width, top + height), black, 1)
    points = np.stack([[px(a) for a in x], [py(b) for b in y]], axis=1).astype(np.int32)
    cv2.polylines(img, [points], False, colour, 2, cv2.LINE_AA)
    cv2.putText(img, label, (left + 10, top + 22), font, 0.6, colour, 2, cv2.LINE_AA)


def tenths_and_growth(values):
    """The mean over each tenth of the run, and the growth from the sixth tenth to the last."""
    n = len(values)
    tenths = [values[k * n // 10:(k + 1) * n // 10].mean() for k in range(10)]
    return tenths, tenths[9] - tenths[5]


def plateau(index, values, name, unit):
    tenths, growth = tenths_and_growth(values)
    print(f"{name}: per tenth of the run " + " ".join(f"{t:.0f}" for t in tenths) + f" {unit}; "
          f"last tenth {tenths[9]:.1f} {unit}, growth over the second half {growth:+.1f} {unit} "
          f"({growth / max(tenths[5], 1e-9) * 100:+.1f} %), maximum {values.max():.1f} {unit} "
          f"at frame {index[int(values.argmax())]}")


def plot(frames_csv, out, title):
    names = ["rss_mb", "map_keyframes", "map_points"]
    index, columns = read_columns(frames_csv, names)
    width, height, margin = 1200, 900, 90
    img = np.full((height, width, 3), 255, np.uint8)
    cv2.putText(img, title, (margin, 35), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (0, 0, 0), 2,
                cv2.LINE_AA)
    panel_h = (height - 60 - 3 * 45) // 3
    labels = ["resident memory [MiB]", "keyframes in the map", "map points"]
    colours = [(40, 40, 200), (200, 90, 30), (40, 140, 40)]
    for k, name in enumerate(names):
        box = (margin, 60 + k * (panel_h + 45), width - margin - 30, panel_h)
        draw_panel(img, box, index, columns[name], labels[k], colours[k])
    cv2.putText(img, "frame", (width // 2, height - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.55,
                (0, 0, 0), 1, cv2.LINE_AA)
    if not cv2.imwrite(out, img):
        sys.exit(f"{out}: cannot write the picture")
    print(f"{out}: {len(index)} frames")
    plateau(index, columns["rss_mb"], "resident memory", "MiB")
    plateau(index, columns["map_keyframes"], "keyframes", "")
    plateau(index, columns["map_points"], "map points", "")


def self_test():
    """A made-up run: memory and map grow over the first 2000 frames, then stay flat."""
    import tempfile
    frames = 5000
    index = np.arange(frames)
    rise = np.minimum(index / 2000.0, 1.0)
    columns = {"rss_mb": 200 + 100 * rise, "map_keyframes": np.round(80 * rise),
               "map_points": np.round(7000 * rise)}
    tenths, growth = tenths_and_growth(columns["rss_mb"])
    failures = []
    if abs(tenths[9] - 300.0) > 1e-9 or abs(growth) > 1e-9:
        failures.append(f"plateau of the flat half: last tenth {tenths[9]}, growth {growth}")
    if not tenths[0] < tenths[1] < tenths[3]:
        failures.append(f"the rise is not in the first tenths: {tenths[:4]}")
    with tempfile.TemporaryDirectory() as work:
        csv_path = os.path.join(work, "frames.csv")
        with open(csv_path, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(["index", "state"] + list(columns))
            for i in index:
                writer.writerow([i, "ok"] + [columns[c][i] for c in columns])
        png = os.path.join(work, "memory.png")
        plot(csv_path, png, "self-test")
        img = cv2.imread(png)
        if img is None or img.shape[:2] != (900, 1200):
            failures.append(f"{png}: not a 1200x900 picture")
        elif (img < 128).mean() < 0.005:
            failures.append("the picture is nearly blank")
    for failure in failures:
        print("FAILED", failure)
    print(f"long_run self-test: {'ok' if not failures else 'FAILED'}")
    return 1 if failures else 0


def run(args):
    data = os.path.join(args.work, f"loop_room_{args.seed}")
    if not os.path.exists(os.path.join(data, "groundtruth.txt")):
        subprocess.run([args.moslam, "synth", "--preset", "loop_room", "--seed", str(args.seed),
                        "--frames", str(args.frames), "--out", data], check=True)
    out = os.path.join(args.work, f"run_{args.seed}")
    subprocess.run([args.moslam, "run", "--dataset", "tum", data, "--settings",
                    os.path.join(data, "settings.yaml"), "--out", out], check=True)
    plot(os.path.join(out, "frames.csv"), os.path.join(out, "memory.png"),
         f"loop_room seed {args.seed}, {args.frames} frames, moslam run (threaded)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run")
    r.add_argument("--moslam", required=True)
    r.add_argument("--work", required=True)
    r.add_argument("--frames", type=int, default=10000)
    r.add_argument("--seed", type=int, default=4)
    sub.add_parser("self-test")
    p = sub.add_parser("plot")
    p.add_argument("frames_csv")
    p.add_argument("out")
    p.add_argument("--title", default="moslam run")
    args = parser.parse_args()
    if args.command == "run":
        run(args)
    elif args.command == "self-test":
        sys.exit(self_test())
    else:
        plot(args.frames_csv, args.out, args.title)


if __name__ == "__main__":
    main()
