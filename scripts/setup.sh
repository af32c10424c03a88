#!/usr/bin/env bash
# One-time setup of a fresh Debian machine for building and testing taut.
# Installs what the Rust toolchain does not bring: a TTF font for the calibration plots, and the
# Python packages the tests use as real peers (pymavlink for MAVLink, mcap to read recordings).
set -euo pipefail
need=()
[ -f /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] || need+=(fonts-dejavu-core)
if [ ${#need[@]} -gt 0 ]; then
    SUDO=""
    [ "$(id -u)" -eq 0 ] || SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}"
fi
# Real peers for the tests, pinned so a fresh machine gets what the tests were written against.
PY_PKGS=(pymavlink==2.4.50 mcap==1.6.0)
if ! python3 -c "import pymavlink, mcap.reader" 2>/dev/null; then
    python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore "${PY_PKGS[@]}"
fi
echo "setup: ok"
