#!/usr/bin/env bash
# Runs every test of the workspace. GPU tests need a Vulkan driver: when the
# machine has none, this installs Mesa's software driver (lavapipe) first, so
# that the GPU tests run everywhere and never skip.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! ls /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json >/dev/null 2>&1; then
    echo "no Vulkan driver found: installing Mesa's lavapipe (mesa-vulkan-drivers)" >&2
    sudo=""
    [ "$(id -u)" = 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null
fi

cargo test --release --workspace "$@"
