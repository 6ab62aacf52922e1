#!/usr/bin/env bash
# Installs freeflex's build and run dependencies from Debian's packages (Debian 12, as root)
# and fetches Debian's source package of SUNDIALS into third_party/sundials-src, which
# freeflex's CMake builds with optimization (-DFREEFLEX_SUNDIALS=bundled, the default;
# Debian's own libsundials_* are compiled at -O0). The source comes from the machine's own
# apt sources: their entries are copied with the type changed to deb-src into
# /etc/apt/sources.list.d/freeflex-deb-src.{sources,list}, then `apt-get source`.
# Does nothing when everything is already present.
#   FREEFLEX_WITH_BENCH=1          also install Google Benchmark
#   FREEFLEX_SUNDIALS=system       skip the SUNDIALS source (build with -DFREEFLEX_SUNDIALS=system)
#   FREEFLEX_SUNDIALS_SOURCE_DIR   where the source goes (default third_party/sundials-src)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
SUDO=""
if [[ $(id -u) != 0 ]]; then SUDO="sudo"; fi

packages=(build-essential cmake pkg-config dpkg-dev libeigen3-dev coinor-libipopt-dev libnlopt-cxx-dev
          libsundials-dev catch2 libtomlplusplus-dev nlohmann-json3-dev libcli11-dev gnuplot-nox
          libmatio-dev pybind11-dev python3-dev python3-numpy python3-scipy python3-matplotlib python3-pytest)
if [[ "${FREEFLEX_WITH_BENCH:-0}" == 1 ]]; then packages+=(libbenchmark-dev); fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

sundials_src=""
if [[ "${FREEFLEX_SUNDIALS:-bundled}" != system ]]; then
  sundials_src=${FREEFLEX_SUNDIALS_SOURCE_DIR:-$root/third_party/sundials-src}
  if [[ -f "$sundials_src/CMakeLists.txt" && -f "$sundials_src/.freeflex-source" ]]; then sundials_src=""; fi
fi

if ((${#missing[@]} == 0)) && [[ -z "$sundials_src" ]]; then
  echo "freeflex: all dependencies present"
  exit 0
fi

# deb-src entries for every deb entry of the machine's apt sources (those that already have
# a deb-src twin are left out), so that apt-get source finds the package where apt-get
# install finds its binaries.
if [[ -n "$sundials_src" ]]; then
  own_sources=/etc/apt/sources.list.d/freeflex-deb-src.sources
  own_list=/etc/apt/sources.list.d/freeflex-deb-src.list
  deb822=$(for f in /etc/apt/sources.list.d/*.sources; do
             [[ -f "$f" && "$f" != "$own_sources" ]] || continue
             # one stanza per paragraph; only the Types field changes
             awk 'BEGIN { RS = ""; ORS = "" }
                  { n = split($0, line, "\n"); out = ""; keep = 0
                    for (i = 1; i <= n; ++i) {
                      if (tolower(line[i]) ~ /^types:/) {
                        if (line[i] ~ /deb-src/) { keep = 0; break }
                        if (line[i] ~ /[: \t]deb([ \t]|$)/) { line[i] = "Types: deb-src"; keep = 1 }
                      }
                      out = out line[i] "\n"
                    }
                    if (keep) print out "\n" }' "$f"
           done)
  oneline=""
  if [[ -f /etc/apt/sources.list ]]; then
    oneline=$(awk '/^[ \t]*deb-src[ \t]/ { have[$0] = 1; next }
                   /^[ \t]*deb[ \t]/ { sub(/deb/, "deb-src"); want[++n] = $0 }
                   END { for (i = 1; i <= n; ++i) if (!(want[i] in have)) print want[i] }' /etc/apt/sources.list)
  fi
  if [[ -z "$deb822" && -z "$oneline" ]]; then
    echo "freeflex: no deb entries in /etc/apt/sources.list or /etc/apt/sources.list.d/*.sources to derive deb-src entries from" >&2
    echo "freeflex: add deb-src entries yourself, or build with -DFREEFLEX_SUNDIALS=system (FREEFLEX_SUNDIALS=system for this script)" >&2
    exit 1
  fi
  header="# Written by freeflex's scripts/install_deps.sh: the machine's deb entries as deb-src, for apt-get source sundials."
  if [[ -n "$deb822" ]]; then printf '%s\n%s' "$header" "$deb822" | $SUDO tee "$own_sources" > /dev/null; fi
  if [[ -n "$oneline" ]]; then printf '%s\n%s\n' "$header" "$oneline" | $SUDO tee "$own_list" > /dev/null; fi
fi

export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
if ((${#missing[@]} > 0)); then
  echo "freeflex: installing ${missing[*]}"
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

if [[ -n "$sundials_src" ]]; then
  # the version of the installed libraries when apt still has it, else the archive's
  version=$(dpkg-query -W -f='${source:Version}' libsundials-dev 2>/dev/null || true)
  parent=$(dirname "$sundials_src")
  mkdir -p "$parent"
  work=$(mktemp -d "$parent/.sundials-fetch.XXXXXX")
  trap 'rm -rf "$work"' EXIT
  echo "freeflex: fetching Debian's source package of SUNDIALS ${version:+($version) }into $sundials_src"
  if ! (cd "$work" && { { [[ -n "$version" ]] && apt-get source -q "sundials=$version"; } || apt-get source -q sundials; }); then
    echo "freeflex: apt-get source sundials failed; build with -DFREEFLEX_SUNDIALS=system to use the installed library" >&2
    exit 1
  fi
  extracted=$(find "$work" -mindepth 1 -maxdepth 1 -type d -name 'sundials-*' | head -n 1)
  if [[ -z "$extracted" || ! -f "$extracted/CMakeLists.txt" ]]; then
    echo "freeflex: apt-get source sundials left no source tree in $work" >&2
    exit 1
  fi
  dsc=$(find "$work" -mindepth 1 -maxdepth 1 -name 'sundials_*.dsc' -printf '%f\n' | head -n 1)
  echo "${dsc%.dsc}" > "$extracted/.freeflex-source"
  rm -rf "$sundials_src"
  mv "$extracted" "$sundials_src"
  echo "freeflex: SUNDIALS source ${dsc%.dsc} in $sundials_src"
fi
