#!/usr/bin/env bash
# Release wasm builds of the library plus their JavaScript glue into www/pkg/ (what the page loads):
#   www/pkg/superpixel_soup.js + _bg.wasm   everything, with the 3D viewer (the page's main thread)
#   www/pkg/soup_worker.js + _bg.wasm       without the viewer (--no-default-features): the
#                                           pipeline for the page's Web Worker, about a sixth of
#                                           the size, so the worker starts (and restarts after a
#                                           cancel) sooner
#   www/pkg/soup_worker_simd.js + _bg.wasm  the same with wasm SIMD (+simd128), which the
#                                           worker loads where the browser validates SIMD
#                                           (www/worker.js): the same results bit for bit, SLIC
#                                           about twice as fast
# Each worker build has its own target folder (target/worker, target/worker-simd), so switching
# features or flags does not rebuild another module. Prints the sizes, raw and gzipped.
# Expects the toolchain from scripts/setup.sh (wasm32 target, matching wasm-bindgen on PATH).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export PATH="${CARGO_HOME:-$HOME/.cargo}/bin:$PATH"

target="${CARGO_TARGET_DIR:-target}"
cargo build --lib --release --target wasm32-unknown-unknown
cargo build --lib --release --target wasm32-unknown-unknown --no-default-features \
    --target-dir "$target/worker"
CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS="-C target-feature=+simd128" \
    cargo build --lib --release --target wasm32-unknown-unknown --no-default-features \
    --target-dir "$target/worker-simd"
wasm-bindgen --target web --out-dir www/pkg \
    "$target/wasm32-unknown-unknown/release/superpixel_soup.wasm"
wasm-bindgen --target web --out-dir www/pkg --out-name soup_worker \
    "$target/worker/wasm32-unknown-unknown/release/superpixel_soup.wasm"
wasm-bindgen --target web --out-dir www/pkg --out-name soup_worker_simd \
    "$target/worker-simd/wasm32-unknown-unknown/release/superpixel_soup.wasm"
# The flags above are ignored where RUSTFLAGS is set: then the "SIMD" build would be the other
# one again, and nothing else would tell. Its target_features section must name simd128.
if ! grep -q simd128 www/pkg/soup_worker_simd_bg.wasm; then
    echo "error: www/pkg/soup_worker_simd_bg.wasm was built without simd128 (is RUSTFLAGS set?)" >&2
    exit 1
fi
for name in superpixel_soup soup_worker soup_worker_simd; do
    file="www/pkg/${name}_bg.wasm"
    echo "ok: $file ($(du -k "$file" | cut -f1) KiB, $(gzip -9 -c "$file" | wc -c | awk '{printf "%d", $1 / 1024}') KiB gzipped)"
done
