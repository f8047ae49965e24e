#!/usr/bin/env bash
# Sets up the toolchain and runs every check and test: formatting, clippy (native and wasm32),
# the API docs without a warning, native tests (unit, integration, doc), the release wasm build,
# the wasm tests in headless Chromium, and the end-to-end page tests. Stops at the first failing
# step and names it.
# The last line is `N passed, N failed`, summed over the test suites.
#
# Browser flags live in two places only: webdriver.json (wasm-bindgen-test-runner) and
# tests/e2e/browser.mjs (Playwright), which reads its flags from webdriver.json.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
export PATH="${CARGO_HOME:-$HOME/.cargo}/bin:$PATH"

logs="$(mktemp -d)"
trap 'rm -rf "$logs"' EXIT
timings=()  # "name<TAB>seconds" per finished step
suites=()   # "name<TAB>passed<TAB>failed" per test suite
total_start=$SECONDS

# step NAME COUNTER COMMAND...: runs COMMAND, shows and logs its output, times it, and stops the
# run if it fails. COUNTER is "-" for a plain step, or the function that reads a test suite's
# pass/fail counts from the log (recorded whether the suite passed or not).
step() {
    local name="$1" counter="$2"
    shift 2
    local start=$SECONDS status=0
    echo
    echo "==> $name"
    "$@" 2>&1 | tee "$logs/last.log" || status=$?
    timings+=("$name"$'\t'"$((SECONDS - start))")
    echo "<== $name: $((SECONDS - start)) s"
    if [ "$counter" != "-" ]; then
        suites+=("$name"$'\t'"$($counter)")
    fi
    if [ "$status" -ne 0 ]; then
        echo
        echo "FAILED step: $name (exit status $status; command: $*)" >&2
        summary 1
        exit 1
    fi
}

# Sums the `test result:` lines of cargo test / wasm-bindgen-test-runner in the last log.
count_cargo() {
    awk '/^test result:/ {
        for (i = 2; i <= NF; i++) {
            if ($i ~ /^passed/) p += $(i - 1)
            if ($i ~ /^failed/) f += $(i - 1)
        }
    } END { printf "%d\t%d", p, f }' "$logs/last.log"
}

# Reads the closing `ℹ pass N` / `ℹ fail N` lines of node's spec reporter in the last log.
count_node() {
    awk '$1 == "ℹ" && NF == 3 && $2 == "pass" { p = $3 }
         $1 == "ℹ" && NF == 3 && $2 == "fail" { f = $3 } END { printf "%d\t%d", p, f }' "$logs/last.log"
}

# summary FAILED_STEP: prints step timings, per-suite counts and the closing counts line.
# A failed step counts as at least one failure, so a failed run never reads "0 failed".
summary() {
    local failed_step="$1" passed=0 failed=0 line name p f
    echo
    echo "== step timings"
    for line in "${timings[@]}"; do
        IFS=$'\t' read -r name p <<<"$line"
        printf '  %-40s %5d s\n' "$name" "$p"
    done
    printf '  %-40s %5d s\n' "total" "$((SECONDS - total_start))"
    echo "== test suites"
    for line in "${suites[@]+"${suites[@]}"}"; do
        IFS=$'\t' read -r name p f <<<"$line"
        printf '  %-40s %d passed, %d failed\n' "$name" "$p" "$f"
        passed=$((passed + p))
        failed=$((failed + f))
    done
    if [ "$failed_step" -eq 1 ] && [ "$failed" -eq 0 ]; then
        failed=1
    fi
    echo "$passed passed, $failed failed"
}

step "setup" - scripts/setup.sh
step "cargo fmt --check" - cargo fmt --all -- --check
step "clippy (native)" - cargo clippy --all-targets -- -D warnings
step "clippy (wasm32)" - cargo clippy --all-targets --target wasm32-unknown-unknown -- -D warnings
# The worker's lean module (scripts/build-web.sh) is the library without the `viewer` feature.
step "clippy (wasm32, worker build)" - \
    cargo clippy --lib --target wasm32-unknown-unknown --no-default-features -- -D warnings
# The API docs, native and wasm32 (the web API and the viewer's GPU part exist only there), with
# every rustdoc warning (a broken intra-doc link, say) an error.
step "cargo doc (native)" - env RUSTDOCFLAGS="-D warnings" cargo doc --no-deps
step "cargo doc (wasm32)" - \
    env RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --target wasm32-unknown-unknown
step "cargo test (native)" count_cargo cargo test
step "wasm release build + wasm-bindgen" - scripts/build-web.sh
# Every test target is built for wasm32 and run by wasm-bindgen-test-runner; only
# #[wasm_bindgen_test] functions run there (browser suites: tests/web*.rs, and tests/parity.rs,
# which also runs natively and asks both for the same depth bits). Doc tests are native. They run
# the build without wasm SIMD; the page's worker build with SIMD (scripts/build-web.sh) is asked
# for the same files, byte for byte, by tests/e2e/page.test.mjs.
step "wasm tests (headless Chromium)" count_cargo \
    env CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUNNER=wasm-bindgen-test-runner \
    cargo test --target wasm32-unknown-unknown --tests
step "e2e page tests (Playwright)" count_node \
    node --test --test-reporter=spec tests/e2e/*.test.mjs

summary 0
