#!/usr/bin/env bash
# Sets up everything rnnpb needs on a fresh Debian machine with Python 3.11:
# the Mesa libraries MuJoCo renders with (offscreen, on the CPU) and a virtual
# environment in .venv with the package and its test tools; with WITH_HANDS=1 also
# .venv-hands, the same with the pose model (rnnpb[hands]). Safe to run again:
# it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3.11}
command -v "$PYTHON" >/dev/null 2>&1 || PYTHON=python3

# System libraries: EGL/Mesa for offscreen MuJoCo rendering; Chromium for the dashboard tests
# (only with WITH_BROWSER=1).
need=(libegl1 libegl-mesa0 libgl1-mesa-dri libgbm1 libosmesa6)
[ "${WITH_BROWSER:-0}" = 1 ] && need+=(chromium)
# The pose model's OpenCV (the desktop build) loads the system's GL and GLib.
[ "${WITH_HANDS:-0}" = 1 ] && need+=(libgl1 libglib2.0-0)
missing=()
for p in "${need[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    if command -v apt-get >/dev/null 2>&1; then
        SUDO=""
        [ "$(id -u)" != 0 ] && SUDO="sudo"
        echo "setup: installing ${missing[*]}"
        $SUDO apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    else
        echo "setup: warning: cannot install ${missing[*]} (no apt-get); rendering may not work" >&2
    fi
fi

# The virtual environment, rebuilt when pyproject.toml changes.
stamp=.venv/.installed
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
    [ -x .venv/bin/python ] || "$PYTHON" -m venv .venv
    .venv/bin/python -m pip install -q --upgrade pip
    .venv/bin/python -m pip install -q -e ".[dev]"
    touch "$stamp"
fi

# The pose model's environment (WITH_HANDS=1): the extra rnnpb[hands] brings protobuf < 5 and
# OpenCV's desktop build, which .venv should not get; scikit-image ships a test photograph.
if [ "${WITH_HANDS:-0}" = 1 ]; then
    stamp=.venv-hands/.installed
    if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ]; then
        [ -x .venv-hands/bin/python ] || "$PYTHON" -m venv .venv-hands
        .venv-hands/bin/python -m pip install -q --upgrade pip
        .venv-hands/bin/python -m pip install -q -e ".[dev,hands]" scikit-image
        touch "$stamp"
    fi
fi
