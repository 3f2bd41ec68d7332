#!/usr/bin/env bash
# The system packages limpid's tests need, installed on Debian when we may
# (root, or sudo without a password); otherwise one line naming them.
#   chromium            report and live-page tests (headless screenshots)
#   cmake, g++          liblsl, built from source for the `lsl` feature
#   fonts-dejavu-core   a sans-serif font for the PNG figures' labels
#   python3-venv        the Python package's test environment
set -euo pipefail
if ! command -v cargo >/dev/null 2>&1; then
  echo "scripts/prerequisites.sh: missing: cargo; install Rust with rustup (https://rustup.rs) first" >&2
  exit 2
fi
missing=""
command -v cmake >/dev/null 2>&1 || missing="$missing cmake"
command -v c++ >/dev/null 2>&1 || missing="$missing g++"
command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || missing="$missing chromium"
[ -e /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] || [ -e /usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf ] || missing="$missing fonts-dejavu-core"
python3 -c "import venv, ensurepip" >/dev/null 2>&1 || missing="$missing python3-venv"
[ -z "$missing" ] && exit 0
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    sudo="sudo -n"
  else
    sudo="none"
  fi
fi
if [ "$sudo" = "none" ] || ! command -v apt-get >/dev/null 2>&1; then
  echo "scripts/prerequisites.sh: missing:$missing; install them first (Debian: apt-get install$missing)" >&2
  exit 2
fi
echo "scripts/prerequisites.sh: installing$missing (apt-get)" >&2
$sudo apt-get update -qq
# shellcheck disable=SC2086
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $missing >/dev/null
