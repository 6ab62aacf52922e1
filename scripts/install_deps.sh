#!/usr/bin/env bash
# Installs freeflex's build and run dependencies from Debian's packages (Debian 12, as root).
# Does nothing when everything is already present.
set -euo pipefail
packages=(build-essential cmake pkg-config libeigen3-dev coinor-libipopt-dev libnlopt-cxx-dev
          libsundials-dev catch2 libtomlplusplus-dev nlohmann-json3-dev libcli11-dev gnuplot-nox)
if [[ "${FREEFLEX_WITH_BENCH:-0}" == 1 ]]; then packages+=(libbenchmark-dev); fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "freeflex: all dependencies present"
  exit 0
fi
echo "freeflex: installing ${missing[*]}"
SUDO=""
if [[ $(id -u) != 0 ]]; then SUDO="sudo"; fi
$SUDO apt-get update -q
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
