#!/usr/bin/env bash
# Installs what Fovea needs on a Debian/Ubuntu machine, only where it is missing.
#   scripts/setup.sh          what `fovea serve` needs: Rust, a C linker, a Vulkan driver
#   scripts/setup.sh --test   also what the tests need: Chromium, Node.js and npm
set -euo pipefail

want_test=0
[[ "${1:-}" == "--test" ]] && want_test=1

sudo=""
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null; then sudo="sudo"; else
    echo "setup: not root and no sudo; install packages by hand if any are missing" >&2
  fi
fi

pkgs=()
command -v cc >/dev/null || pkgs+=(build-essential)
command -v curl >/dev/null || pkgs+=(curl ca-certificates)
# The Vulkan loader, and Mesa's software driver (lavapipe) when no Vulkan driver is installed:
# with it every machine has an adapter, GPU or not.
ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' || pkgs+=(libvulkan1)
compgen -G '/usr/share/vulkan/icd.d/*.json' >/dev/null || compgen -G '/etc/vulkan/icd.d/*.json' >/dev/null \
  || pkgs+=(mesa-vulkan-drivers)
if [[ $want_test -eq 1 ]]; then
  command -v chromium >/dev/null || pkgs+=(chromium)
  command -v node >/dev/null || pkgs+=(nodejs)
  command -v npm >/dev/null || pkgs+=(npm)
fi

if [[ ${#pkgs[@]} -gt 0 ]]; then
  echo "setup: installing ${pkgs[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${pkgs[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null; then
  if [[ -x "$HOME/.cargo/bin/cargo" ]]; then
    echo "setup: Rust is in ~/.cargo/bin; add it to PATH (source ~/.cargo/env)" >&2
  else
    echo "setup: installing Rust with rustup"
    curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal
  fi
fi
