#!/usr/bin/env bash
# Installs, from Debian's packages, whatever leeway needs to build and test that is not there yet.
# Idempotent and non-interactive; when everything is installed it only asks dpkg and returns.
# libqhull-dev: Debian's mujoco::mujoco target names /usr/include/libqhull_r as an include path.
# libosmesa6-dev: offscreen OpenGL without a display for `leeway render` (PNG plots need none; MuJoCo links
# no GL itself); zlib1g-dev: PNG compression. libopenmpi-dev, openmpi-bin: `leeway batch` and
# leeway-tune over MPI ranks (optional for the build; the MPI tests run when mpirun is there).
# pybind11-dev, python3-dev, python3-numpy, python3-pytest: the Python module (python/) and its tests,
# built against and run with Debian's /usr/bin/python3 (optional: without pybind11 it is skipped).
# locales: the locale sources from which the plot test compiles a decimal-comma locale (de_DE)
# with localedef when none is installed.
# ffmpeg: `leeway simulate --video` pipes its frames to it (optional: without it no video is written).
# libjs-three: three.js, which `leeway view` inlines into its page; chromium: the browser the viewer's
# tests open the page in, headless (optional: without it those tests are skipped).
# `--sanitizers` adds what scripts/sanitize.sh needs: clang and its sanitizer/libFuzzer runtimes
# (gcc's ASan/UBSan/TSan runtimes come with build-essential).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config clang-format python3
  libmujoco-dev libqhull-dev libeigen3-dev libompl-dev libnlopt-cxx-dev liburdfdom-dev
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev
  libosmesa6-dev zlib1g-dev libopenmpi-dev openmpi-bin
  pybind11-dev python3-dev python3-numpy python3-pytest ffmpeg locales libjs-three chromium
)
for arg in "$@"; do
  case "$arg" in
    --sanitizers) packages+=(clang libclang-rt-14-dev) ;;
    *)
      echo "setup: unknown option '$arg' (only --sanitizers)" >&2
      exit 2
      ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages are installed"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  sudo_cmd=(sudo)
fi
echo "setup: installing ${missing[*]}"
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
