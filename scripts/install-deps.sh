#!/usr/bin/env bash
# Installs every Debian package needed to build, test and run lsgd.
# Idempotent: packages already present are left alone. Needs root (or sudo).
set -euo pipefail

packages=(
  cmake g++ make pkgconf
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev
  libopencv-features2d-dev libopencv-calib3d-dev
  libopencv-contrib-dev  # opencv_ximgproc: `lsgd bench` times OpenCV's SLIC (optional)
  libcli11-dev libyaml-cpp-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev
  libbenchmark-dev
  libhwy-dev
  libmatio-dev  # MATLAB .mat ground truth (lsgd gt); brings zlib1g-dev
  libsqlite3-dev  # detector databases (lsgd run --database, lsgd_io)
  libjpeg-dev  # libjpeg-turbo's warnings tell a damaged JPEG (lsgd_io)
  libhnswlib-dev  # the index search mode's graph (header-only)
  pybind11-dev python3-dev python3-numpy  # the Python module (python/), for /usr/bin/python3
  python3-pytest python3-matplotlib  # its tests and python/examples/evaluate.py
  python3-pil  # scripts/eval_suite.py and mixed_map.py build the suite's sequences
  python3-distributed  # lsgd.sweep(client=...): cells on a Dask cluster (issue 34)
  clang libclang-rt-14-dev  # scripts/ci-hardening.sh: libFuzzer targets in fuzz/
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages already installed"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
echo "install-deps: installing ${missing[*]}"
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
