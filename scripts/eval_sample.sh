#!/usr/bin/env bash
# Sets up, builds, then evaluates the bundled sample trajectory (data/sample, made by
# tools/make_sample_trajectory.cc) against its ground truth, prints the error tables and writes
# plots into out/. (The main job on the bundled input is scripts/demo.sh.)
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
scripts/build.sh release
mkdir -p out
moslam=build/apps/moslam/moslam
gt=data/sample/groundtruth.txt
est=data/sample/estimate.txt

echo
echo "== Absolute trajectory error, SE(3)-aligned =="
"$moslam" eval ate "$gt" "$est" --align se3 --plot out/sample_ate.png
echo
echo "== Absolute trajectory error, Sim(3)-aligned (scale corrected) =="
"$moslam" eval ate "$gt" "$est" --align sim3 --plot out/sample_ate_sim3.svg
echo
echo "== Relative pose error over 1 s =="
"$moslam" eval rpe "$gt" "$est" --delta 1 --delta-unit s --plot out/sample_rpe.png
echo
echo "Plots: out/sample_ate.png out/sample_ate_sim3.svg out/sample_rpe.png"
