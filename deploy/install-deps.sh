#!/usr/bin/env bash
# Installs every build and runtime dependency of Glimpse from Debian 12 packages.
# Idempotent: packages already present are skipped. Used by README, .ci/run and the Dockerfile.
#   deploy/install-deps.sh            build + test dependencies
#   deploy/install-deps.sh --runtime  only the shared libraries the binaries need (container runtime stage)
set -euo pipefail

build_pkgs=(
  build-essential cmake ninja-build pkg-config git ca-certificates
  libeigen3-dev libpcl-dev libnanoflann-dev libqhull-dev libembree-dev liblinear-dev
  libgrpc++-dev libprotobuf-dev protobuf-compiler protobuf-compiler-grpc
  libsqlite3-dev sqlite3 zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev
  prometheus-cpp-dev
  python3 python3-grpcio python3-grpc-tools python3-yaml
)
runtime_pkgs=(
  libgrpc++1.51 libprotobuf32 libsqlite3-0 libqhull-r8.0 libgomp1 libembree3-3 liblinear4
  libpcl-common1.13 libpcl-features1.13 libpcl-search1.13 libpcl-kdtree1.13
  libpcl-filters1.13 libpcl-segmentation1.13 libpcl-sample-consensus1.13 libpcl-octree1.13
  libpcl-io1.13  # the client's reader of PCD binary_compressed frames (PCL's; it brings VTK's libraries)
  libprometheus-cpp-core1.0 libprometheus-cpp-pull1.0 ca-certificates
  sqlite3  # the shell deploy/model-sync.sh publishes and pulls model stores with
)

pkgs=("${build_pkgs[@]}")
if [[ "${1:-}" == "--runtime" ]]; then pkgs=("${runtime_pkgs[@]}"); fi

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#pkgs[@]} packages already installed"
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
