#!/usr/bin/env bash
# Installs what Fovea needs on Debian 12, Debian 13 or Ubuntu 24.04, only where it is missing.
#   scripts/setup.sh          what `fovea serve` needs: a C toolchain, the Vulkan loader and a
#                             Vulkan driver, and a Rust toolchain at least as new as Cargo.toml's
#                             rust-version (rustup, into ~/.cargo, when the system's is older)
#   scripts/setup.sh --test   also what the tests need: a Chromium for the browser tests, nginx
#                             for the fleet test, and (in a Python virtual environment)
#                             kubernetes-validate and checkov for the deployment checks
# Prints `export PATH=…` advice when it installed Rust; the other scripts source ~/.cargo/env.
set -euo pipefail
cd "$(dirname "$0")/.."

want_test=0
[[ "${1:-}" == "--test" ]] && want_test=1

sudo=""
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null; then sudo="sudo"; else
    echo "setup: not root and no sudo; install packages by hand if any are missing" >&2
  fi
fi

# shellcheck disable=SC1091
. /etc/os-release 2>/dev/null || ID=unknown

pkgs=()
command -v cc >/dev/null || pkgs+=(build-essential)
# openh264 (H.264 frames) is C++, compiled from source by its crate.
command -v c++ >/dev/null || pkgs+=(g++)
# Its x86 assembly (SIMD transforms and motion search) is built when nasm is there, else left
# out silently: measured here, H.264 encoding went from 1.4–1.9× JPEG q85's time to 0.9×.
command -v nasm >/dev/null || pkgs+=(nasm)
command -v curl >/dev/null || pkgs+=(curl ca-certificates)
command -v pkg-config >/dev/null || pkgs+=(pkg-config)
# The Vulkan loader, and Mesa's software driver (lavapipe) when no Vulkan driver is installed:
# with it every machine has an adapter, GPU or not.
ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' || pkgs+=(libvulkan1)
compgen -G '/usr/share/vulkan/icd.d/*.json' >/dev/null || compgen -G '/etc/vulkan/icd.d/*.json' >/dev/null \
  || pkgs+=(mesa-vulkan-drivers)
browser=""
if [[ $want_test -eq 1 ]]; then
  for b in chromium chromium-browser google-chrome google-chrome-stable; do
    if command -v "$b" >/dev/null && "$b" --version >/dev/null 2>&1; then browser=$(command -v "$b"); break; fi
  done
  # Debian packages Chromium as a .deb; Ubuntu 24.04 only as a snap (see below).
  [[ -z "$browser" && "$ID" == "debian" ]] && pkgs+=(chromium)
  # The fleet test's balancer (run by the test in its own prefix, not as the system service).
  command -v nginx >/dev/null || [[ -x /usr/sbin/nginx ]] || pkgs+=(nginx)
  # A virtual environment for the deployment checks' tools (Debian splits venv out of python3).
  if [[ ! -x "${FOVEA_DEPLOY_TOOLS:-$HOME/.cache/fovea/deploy-tools}/bin/checkov" ]]; then
    probe=$(mktemp -d)
    python3 -m venv "$probe/v" >/dev/null 2>&1 || pkgs+=(python3 python3-venv)
    rm -rf "$probe"
  fi
fi

if [[ ${#pkgs[@]} -gt 0 ]]; then
  echo "setup: installing ${pkgs[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${pkgs[@]}" >/dev/null
fi

if [[ $want_test -eq 1 && -z "$browser" && "$ID" != "debian" ]]; then
  # Ubuntu 24.04 has no Chromium .deb and CI has no snapd: Playwright's build of Chromium,
  # fetched by its Python package into ~/.cache/ms-playwright. The tests find it via CHROMIUM.
  echo "setup: no Chromium .deb on $ID; fetching Playwright's Chromium (headless shell)"
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends python3-venv >/dev/null
  venv="$HOME/.cache/fovea/playwright"
  [[ -x "$venv/bin/playwright" ]] || { python3 -m venv "$venv" && "$venv/bin/pip" install -q playwright; }
  $sudo "$venv/bin/playwright" install-deps chromium-headless-shell >/dev/null
  "$venv/bin/playwright" install chromium-headless-shell >/dev/null
  shell=$(compgen -G "$HOME/.cache/ms-playwright/chromium_headless_shell-*/chrome-*/chrome-headless-shell" | head -n1)
  echo "setup: browser tests use $shell (export CHROMIUM=$shell)"
fi

if [[ $want_test -eq 1 ]]; then
  # The deployment checks' tools, pinned, in their own virtual environment.
  tools=${FOVEA_DEPLOY_TOOLS:-$HOME/.cache/fovea/deploy-tools}
  if [[ ! -x "$tools/bin/checkov" || ! -x "$tools/bin/kubernetes-validate" ]]; then
    echo "setup: installing kubernetes-validate and checkov into $tools"
    python3 -m venv "$tools"
    "$tools/bin/pip" install -q --disable-pip-version-check \
      kubernetes-validate==1.37.0 checkov==3.3.30 jsonpatch==1.48 PyYAML==6.0.4
  fi
fi

# Rust: the toolchain must be at least Cargo.toml's rust-version (the newest minimum in the
# locked dependency tree); distributions ship older ones (Debian 12: 1.63, Debian 13: 1.85,
# Ubuntu 24.04: 1.75), so rustup installs a current one beside them.
need=$(sed -n 's/^rust-version = "\(.*\)"/\1/p' Cargo.toml)
[[ -f "$HOME/.cargo/env" ]] && . "$HOME/.cargo/env"
# (`|| true`: without cargo the pipeline fails, and under `set -e -o pipefail` that would end
# the script silently right here on a fresh machine.)
have=$(cargo --version 2>/dev/null | sed -n 's/^cargo \([0-9]*\.[0-9]*\).*/\1/p' || true)
older() { [[ "$(printf '%s\n%s\n' "$1" "$2" | sort -V | head -n1)" != "$2" ]]; }
if [[ -z "$have" ]] || older "$have" "$need"; then
  echo "setup: Rust ${have:-missing}, Fovea needs $need or newer: installing the stable toolchain with rustup"
  if command -v rustup >/dev/null; then
    rustup toolchain install stable --profile minimal && rustup default stable
  else
    # The script sh.rustup.rs serves, from the host rustup fetches the toolchain from anyway:
    # a network that lets the toolchain through (an allow-list, a proxy) lets this through.
    curl --proto '=https' --tlsv1.2 -sSf https://static.rust-lang.org/rustup/rustup-init.sh |
      sh -s -- -y --profile minimal
  fi
  echo "setup: run 'source ~/.cargo/env' (or open a new shell) to use it"
fi

# openh264's build leaves its assembly out, with one line in cargo's build output, when nasm is
# missing, and cargo does not rebuild it when nasm arrives later (measured here: 720p H.264
# encodes 1.4-1.9x slower without it). A build made before nasm was installed is dropped, so
# the next `cargo build` makes it with the assembly.
nasm_bin=$(command -v nasm || true)
if [[ -n "$nasm_bin" ]] && command -v cargo >/dev/null; then
  for out in target/*/build/openh264-sys2-*/output; do
    [[ -f "$out" ]] && grep -q 'Failed to compile NASM' "$out" && [[ "$nasm_bin" -nt "$out" ]] || continue
    profile=$(echo "$out" | cut -d/ -f2)
    echo "setup: openh264 in target/$profile was built before nasm was installed; rebuilding it"
    cargo clean --quiet -p openh264-sys2 --profile "$([[ $profile == debug ]] && echo dev || echo "$profile")"
  done
fi
