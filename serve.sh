#!/usr/bin/env bash
# Builds the web app and serves it on http://localhost:8080 (env PORT changes the port).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"

source scripts/setup.sh --serve
scripts/build-web.sh
exec python3 scripts/serve.py --port "${PORT:-8080}"
