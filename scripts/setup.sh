#!/usr/bin/env bash
# Installs what building, serving and testing superpixel-soup needs, and nothing that is
# already there. Safe to run again and again; quick when everything is installed.
#
#   scripts/setup.sh            everything: wasm toolchain, lint components, Python,
#                               Chromium + ChromeDriver, Node.js + npm packages (what ./check.sh needs)
#   scripts/setup.sh --serve    only what ./serve.sh needs: wasm target, wasm-bindgen, Python
#
# Can also be sourced (`source scripts/setup.sh [--serve]`): then ~/.cargo/bin stays on PATH.
# Assumes Debian with Rust installed by rustup. Never installs Debian's `binaryen` (its wasm-opt
# 108 produces modules that fail in the browser; see TOOLCHAIN.md).

set -euo pipefail

soup_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export PATH="${CARGO_HOME:-$HOME/.cargo}/bin:$PATH"

soup_ok() { echo "ok: $*"; }
soup_die() {
    echo "setup: $*" >&2
    exit 1
}

# Runs a command as root: directly when we are root, else through sudo.
soup_as_root() {
    if [ "$(id -u)" -eq 0 ]; then
        "$@"
    elif command -v sudo >/dev/null; then
        sudo "$@"
    else
        soup_die "need root (or sudo) to run: $*"
    fi
}

soup_apt_updated=0
# Installs Debian packages, running `apt-get update` once per setup run first.
soup_apt_install() {
    command -v apt-get >/dev/null || soup_die "apt-get not found; install by hand: $*"
    if [ "$soup_apt_updated" -eq 0 ]; then
        soup_as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
        soup_apt_updated=1
    fi
    soup_as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@" >/dev/null
}

soup_rust() {
    command -v rustup >/dev/null || soup_die "rustup not found: install Rust from rustup.rs first"
    local installed
    installed="$(rustup target list --installed)"
    if ! grep -qx wasm32-unknown-unknown <<<"$installed"; then
        rustup target add wasm32-unknown-unknown
    fi
    soup_ok "rust target wasm32-unknown-unknown"
}

soup_lint_components() {
    local installed
    installed="$(rustup component list --installed)"
    for component in clippy rustfmt; do
        if ! grep -q "^$component" <<<"$installed"; then
            rustup component add "$component"
        fi
    done
    soup_ok "rustup components clippy, rustfmt"
}

# wasm-bindgen-cli must be exactly the version of the `wasm-bindgen` crate pinned in Cargo.toml.
soup_wasm_bindgen() {
    local want have
    want="$(sed -n 's/^wasm-bindgen *=.*"=\([0-9][0-9.]*\)".*/\1/p' "$soup_root/Cargo.toml" | head -n1)"
    [ -n "$want" ] || soup_die 'Cargo.toml must pin wasm-bindgen exactly (wasm-bindgen = "=X.Y.Z")'
    have="$(wasm-bindgen --version 2>/dev/null | awk '{print $2}' || true)"
    if [ "$have" != "$want" ] || ! command -v wasm-bindgen-test-runner >/dev/null; then
        echo "installing wasm-bindgen-cli $want (found: ${have:-none}); takes a few minutes"
        # No --locked: a dependency locked by wasm-bindgen-cli is missing from crates.io.
        cargo install wasm-bindgen-cli --version "$want" --force
    fi
    soup_ok "wasm-bindgen $want"
}

soup_python() {
    command -v python3 >/dev/null || soup_apt_install python3
    soup_ok "python3 ($(python3 --version 2>&1))"
}

soup_chromium() {
    if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then
        echo "installing Debian chromium + chromium-driver"
        soup_apt_install chromium chromium-driver
    fi
    soup_ok "chromium + chromedriver ($(/usr/bin/chromium --version 2>/dev/null | awk '{print $2}'))"
}

soup_node() {
    if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
        echo "installing Debian nodejs + npm"
        soup_apt_install nodejs npm
    fi
    if [ -f "$soup_root/package.json" ]; then
        local stamp="$soup_root/node_modules/.package-lock.json"
        if [ ! -f "$stamp" ] || [ "$soup_root/package-lock.json" -nt "$stamp" ]; then
            (cd "$soup_root" && npm ci --no-audit --no-fund --loglevel=error)
        fi
    fi
    soup_ok "node $(node --version), npm packages"
}

soup_setup() {
    case "${1:-}" in
    --serve)
        soup_rust
        soup_wasm_bindgen
        soup_python
        ;;
    "")
        soup_rust
        soup_lint_components
        soup_wasm_bindgen
        soup_python
        soup_chromium
        soup_node
        ;;
    *) soup_die "unknown option: $1 (use --serve or nothing)" ;;
    esac
}

soup_setup "$@"
