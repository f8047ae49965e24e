#!/usr/bin/env bash
# Release wasm build of the library plus its JavaScript glue into www/pkg/ (what the page loads).
# Expects the toolchain from scripts/setup.sh (wasm32 target, matching wasm-bindgen on PATH).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export PATH="${CARGO_HOME:-$HOME/.cargo}/bin:$PATH"

cargo build --lib --release --target wasm32-unknown-unknown
wasm-bindgen --target web --out-dir www/pkg \
    "${CARGO_TARGET_DIR:-target}/wasm32-unknown-unknown/release/superpixel_soup.wasm"
echo "ok: www/pkg/superpixel_soup_bg.wasm ($(du -k www/pkg/superpixel_soup_bg.wasm | cut -f1) KiB)"
