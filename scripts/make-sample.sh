#!/usr/bin/env bash
# Regenerates the page's built-in sample pair, www/sample/ (frame1.png, frame2.png,
# intrinsics.txt), with the project's own generator: `soup synth --scene street --size 768x328`
# (a camera driving down a street while two cars move). tests/sample.rs checks that the
# committed files are byte for byte what the generator makes now; run this when it fails after a
# deliberate change to the synthetic scenes.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

cargo build --release --bin soup
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"${CARGO_TARGET_DIR:-target}/release/soup" synth "$tmp" --scene street --size 768x328
mkdir -p www/sample
cp "$tmp/street/frame1.png" "$tmp/street/frame2.png" "$tmp/street/intrinsics.txt" www/sample/
ls -l www/sample
