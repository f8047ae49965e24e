#!/usr/bin/env python3
"""How much the MRE of each evaluation case depends on the random seeds: `soup eval` is run with
the default seeds and with seeds 1 .. N-1 (the motion fitting's RANSAC, `init.seed`, and the
refinement's perturbations, `refine.seed`, both set to the same value), everything else at its
defaults or at the overrides given with --params. Prints a Markdown table: per case the MRE at
the default seeds, and the mean, smallest and largest over all N runs.

The result is deterministic for one seed; across seeds it is not the same, and on scenes where
the scale energy has several nearly equal minima (movers whose scale two frames barely pin) it
moves a lot. A change to the method is only an improvement when it holds over seeds: compare
means, not one run.

Usage: scripts/seeds.py CASE_DIR... [--seeds N] [--params FILE] [--preset P] [--superpixels N]
                        [--gt-flow] [--json OUT]
  (needs a release build: cargo build --release --bin soup)
"""

import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sweep import evaluate_seeds, option  # noqa: E402


def main():
    args = sys.argv[1:]
    runs = int(option(args, "--seeds", "5"))
    params_file = option(args, "--params", None)
    json_out = option(args, "--json", None)
    extra = []
    for name in ("--preset", "--superpixels"):
        value = option(args, name, None)
        if value is not None:
            extra += [name, value]
    gt_flow = "--gt-flow" in args
    cases = [a for a in args if not a.startswith("--")]
    if not cases or runs < 1:
        sys.exit(__doc__)
    base = {}
    if params_file:
        with open(params_file) as f:
            base = json.load(f)
    results = evaluate_seeds(cases, base, gt_flow, runs, extra)
    print(f"| case | default seeds | mean over {runs} seeds | smallest | largest |")
    print("| --- | --- | --- | --- | --- |")
    table = {}
    for case in results[0]:
        mres = [r[case] for r in results]
        table[case] = mres
        name = os.path.basename(os.path.normpath(case))
        print(
            f"| {name} | {mres[0]:.4f} | {sum(mres) / len(mres):.4f} | {min(mres):.4f} | "
            f"{max(mres):.4f} |"
        )
    if json_out:
        with open(json_out, "w") as f:
            json.dump(table, f, indent=1)


if __name__ == "__main__":
    main()
