#!/usr/bin/env bash
# Installs the Debian bookworm packages BE-SLAM needs. Idempotent: does nothing when all are present (no
# apt-get update either), so repeated runs and CI re-runs cost a second.
#   scripts/install-deps.sh          what the build and the demo need (scripts/demo.sh): every plugin but
#                                    detector_lidar
#   scripts/install-deps.sh --lidar  that and PCL, for detector_lidar (libpcl-dev pulls in about 200 packages:
#                                    VTK, Qt, a Java runtime)
#   scripts/install-deps.sh --test   that, PCL and what the tests need: GoogleTest, clang (the sanitised build
#                                    and the fuzz targets), clang-format, Chromium (the report's browser test),
#                                    pytest (the Python package's tests)
set -euo pipefail

packages=(
  build-essential cmake pkg-config ccache
  libeigen3-dev libopencv-dev libceres-dev libyaml-cpp-dev
  libboost-dev libboost-filesystem-dev liboctomap-dev nlohmann-json3-dev
  libjs-three libjs-chart.js   # the HTML report's libraries
  pybind11-dev python3-dev python3-numpy   # the Python package (platform/python)
)
case "${1:-}" in
  "") ;;
  --lidar) packages+=(libpcl-dev) ;;
  --test) packages+=(libpcl-dev libgtest-dev libgmock-dev libbenchmark-dev clang libclang-rt-14-dev clang-format
    chromium python3-pytest) ;;
  *) echo "install-deps: unknown option '$1' (expected none, --lidar or --test)" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
