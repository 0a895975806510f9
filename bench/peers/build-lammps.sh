#!/usr/bin/env bash
# Builds LAMMPS 4Feb2025 with the BPM, GRANULAR and MOLECULE packages (Debian 12's binary lammps,
# 20220106, has no BPM) from Debian trixie's source tarball into /tmp/lmp, MPI on, OpenMP off
# (bpm/rotational has no threaded variant: LAMMPS scales it through MPI ranks). About 12 minutes
# on 2 cores. Needs root for apt (it adds a deb-src entry for trixie).
set -euo pipefail
prefix=${LAMMPS_BUILD_DIR:-/tmp/lmp}
mirror=$(awk '/^URIs:/{print $2; exit}' /etc/apt/sources.list.d/debian.sources)
cat > /etc/apt/sources.list.d/trixie-src.sources <<SOURCES
Types: deb-src
URIs: $mirror
Suites: trixie
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SOURCES
apt-get update -qq
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends libopenmpi-dev \
  openmpi-bin cmake ninja-build g++ >/dev/null
mkdir -p "$prefix" && cd "$prefix"
# The .dsc of this version is gone from the mirror; the tarballs are still there.
apt-get source --download-only lammps=20250204+dfsg.1-2 || true
tar xf lammps_20250204+dfsg.1.orig.tar.xz
mkdir -p lammps-4Feb2025/build-bpm && cd lammps-4Feb2025/build-bpm
cmake ../cmake -G Ninja -DCMAKE_BUILD_TYPE=Release -DBUILD_MPI=on -DBUILD_OMP=off \
  -DPKG_BPM=on -DPKG_GRANULAR=on -DPKG_MOLECULE=on -DLAMMPS_MACHINE=bpm \
  -DBUILD_SHARED_LIBS=off >/dev/null
nice -n 15 ninja -j"$(nproc)" >/dev/null
echo "$prefix/lammps-4Feb2025/build-bpm/lmp_bpm"
