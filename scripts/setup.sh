#!/usr/bin/env bash
# Installs the Debian 12 packages moslam needs, only those missing, with apt-get. Nothing else is
# downloaded from anywhere. Safe to run again: with everything present it does nothing.
set -euo pipefail

PACKAGES=(
  # toolchain
  g++ cmake make pkg-config clang-format
  # libraries (README "Dependencies" says why each)
  libeigen3-dev libopencv-dev libspdlog-dev libfmt-dev nlohmann-json3-dev libcli11-dev
  libceres-dev libcereal-dev liboctomap-dev
  libopencv-contrib-dev libtorch-dev
  # net/'s fused 1x1 convolutions: oneDNN's headers (libtorch already links its library)
  libdnnl-dev
  # the BLAS libtorch and CHOLMOD get through Debian's alternatives (ATLAS otherwise; README)
  libopenblas0-openmp
  libosmesa6-dev
  # the live viewer (src/moslam/viewer): HTTP/WebSocket server (header only, on standalone asio)
  # and three.js served from its installed files
  libwebsocketpp-dev libasio-dev libjs-three
  # moslam run --dataset rosbag|kinect (src/moslam/sensors): ROS 1 bags with their image messages,
  # and the Kinect v1; pluginlib-dev is what librosbag-storage-dev's headers include
  librosbag-dev libsensor-msgs-dev pluginlib-dev libfreenect-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # the bad-input corpus (tools/bad_input_corpus, docs/ROBUSTNESS.md): images and .npy files
  python3-numpy python3-opencv
  # the parsers' fuzzers (scripts/fuzz.sh): clang and its libFuzzer and sanitizer runtimes
  clang libclang-rt-14-dev
  # the viewer's browser test (viewer/browser_test skips without it)
  chromium
  # the Python module (python/) and its tests
  pybind11-dev python3-dev python3-pytest
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
