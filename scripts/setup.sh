#!/usr/bin/env bash
# Installs everything mdem needs on Debian 12 (build, tests, benchmarks, and the service parts that
# later milestones add), then configures and builds a Release build into ./build.
# Idempotent and non-interactive: safe to run again; apt is skipped when every package is present.
# Usage: scripts/setup.sh     (from any directory; uses sudo for apt when not root)
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."

PACKAGES=(
  build-essential        # g++ (with libgomp for OpenMP), make
  cmake                  # >= 3.25
  pkg-config
  libeigen3-dev          # engine: linear algebra, quaternions
  libgtest-dev           # tests
  libgmock-dev           # tests
  libbenchmark-dev       # bench/
  libhwy-dev             # engine: SIMD with run-time dispatch (Google Highway)
  nlohmann-json3-dev     # CLI JSON output
  libsqlite3-dev         # results database (service)
  libspdlog-dev          # logging (service)
  libfmt-dev             # formatting (spdlog)
  libprotobuf-dev        # job spec messages
  protobuf-compiler
  libgrpc++-dev          # mdemd daemon
  protobuf-compiler-grpc
  libyaml-cpp-dev        # job specs from YAML files
  clang-format           # code style (.clang-format)
  gnuplot-nox            # mdem plot
  python3                # tests: the independent reader of mdem export's files
  python3-ase            # tests: ASE (3.22) reads mdem export's extended XYZ
  zlib1g-dev             # mdemd: CRC-32 of checkpoints
  openssl                # tests: a throwaway TLS certificate for mdemd
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q '^install ok installed$'; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} > 0)); then
  echo "setup: installing ${missing[*]}"
  SUDO=()
  if [[ $(id -u) -ne 0 ]]; then
    if ! command -v sudo >/dev/null 2>&1; then
      echo "setup: not root and sudo is not available; install as root: apt-get install ${missing[*]}" >&2
      exit 1
    fi
    SUDO=(sudo)
  fi
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
  "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q "${missing[@]}" </dev/null
else
  echo "setup: all ${#PACKAGES[@]} apt packages already installed"
fi

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
echo "setup: built into ./build (./build/mdem, tests: ctest --test-dir build)"
