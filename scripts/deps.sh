#!/usr/bin/env bash
# Installs the Debian packages sere needs, only those missing. Needs root (or sudo).
# Arguments name extra packages a target needs: `make deps CC=clang` adds clang and libomp-dev
# (Debian's clang does not pull in LLVM's OpenMP runtime, which its -fopenmp links), and
# `make examples-check` adds cmake.
set -euo pipefail
need=(gcc g++ make pkg-config libgomp1 libhwloc-dev libbenchmark-dev libcriterion-dev
      libeigen3-dev libembree-dev libpng-dev libcairo2-dev python3-vtk9 libassimp-dev libhypre-dev libopenmpi-dev
      openmpi-bin "$@")
missing=()
for p in "${need[@]}"; do
	dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "sere: installing missing Debian packages: ${missing[*]}" >&2
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
