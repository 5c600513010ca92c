#!/usr/bin/env bash
# Runs every test of the workspace. GPU tests need a Vulkan driver: when the
# machine has none, this installs Mesa's software driver (lavapipe) first, so
# that the GPU tests run everywhere and never skip; likewise Xvfb for the
# viewer's window test.
set -euo pipefail
cd "$(dirname "$0")/.."

# Either folder may hold the drivers' manifests (`ls` of both fails when one
# is empty, so each is asked on its own).
if ! compgen -G '/usr/share/vulkan/icd.d/*.json' >/dev/null && ! compgen -G '/etc/vulkan/icd.d/*.json' >/dev/null; then
    echo "no Vulkan driver found: installing Mesa's lavapipe (mesa-vulkan-drivers)" >&2
    sudo=""
    [ "$(id -u)" = 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null
fi

# The viewer's smoke test opens a real window on a virtual X display.
if ! command -v xvfb-run >/dev/null 2>&1; then
    echo "no xvfb-run found: installing Xvfb (xvfb, xauth)" >&2
    sudo=""
    [ "$(id -u)" = 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq xvfb xauth >/dev/null
fi

# Without a desktop session, Mesa's Vulkan device-select layer makes
# libwayland print an XDG_RUNTIME_DIR error at every GPU test; the layer has
# nothing to choose by there (the app switches it off the same way).
if [ -z "${XDG_RUNTIME_DIR:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ]; then
    export NODEVICE_SELECT="${NODEVICE_SELECT:-1}"
fi

cargo test --release --workspace "$@"
