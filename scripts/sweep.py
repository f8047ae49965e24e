#!/usr/bin/env python3
"""Robustness of the soup's defaults: every numeric parameter of the unit-scale soup (`init`), the
scale solve, the refinement and the fusion (`ensemble`) is moved by -20 % and +20 % in turn (one at a time, integers rounded), and the MRE of
each evaluation case is compared with the MRE at the defaults. Prints a Markdown table: per
parameter, the largest change of any case's MRE and the case it happened on.

Usage: scripts/sweep.py CASE_DIR... [--gt-flow] [--only NAME,...] [--seeds N]
  (NAME as the table prints it, `scales.sigma`, or without its group, `sigma`)
  (needs a release build: cargo build --release --bin soup)

With --seeds N every setting is evaluated at the default seeds and at seeds 1 .. N-1 (see
scripts/seeds.py) and compared by its mean MRE per case: where one seed is one draw, a change
measured at the default seeds alone mostly measures which draw it lands on.

Cases are evaluation folders: the synthetic scenes of `soup synth` and, when present, the public
cases in ../shared/eval/. Each run of `soup eval` takes the cases' time (seconds per case), so a
full sweep over ~48 parameters takes about (1 + 2 × 48) evaluations.
"""

import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOUP = os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "soup")
# Parameters that are not tunables: seeds, and switches whose ±20 % has no meaning.
SKIP = {"seed"}


def evaluate(cases, params, gt_flow, extra=()):
    """MRE per case for the given parameter overrides (a nested dict); `extra` are more options
    of `soup eval` (for example `--preset medium`)."""
    with tempfile.TemporaryDirectory() as tmp:
        params_file = os.path.join(tmp, "params.json")
        out_file = os.path.join(tmp, "out.json")
        with open(params_file, "w") as f:
            json.dump(params, f)
        cmd = [SOUP, "eval", *cases, "--params", params_file, "--json", out_file]
        if gt_flow:
            cmd.append("--gt-flow")
        cmd.extend(extra)
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        with open(out_file) as f:
            return {r["case"]: r["metrics"]["mre"] for r in json.load(f)}


def merged(base, overrides):
    """`base` with the nested dict `overrides` merged into it (a new dict)."""
    out = dict(base)
    for key, value in overrides.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merged(out[key], value)
        else:
            out[key] = value
    return out


def evaluate_seeds(cases, params, gt_flow, runs, extra=()):
    """[`evaluate`] at the default seeds and at seeds 1 .. runs-1 (`init.seed` and
    `refine.seed` set to the same value): the list of the runs' MRE per case."""
    results = [evaluate(cases, params, gt_flow, extra)]
    for seed in range(1, runs):
        seeds = {"init": {"seed": seed}, "refine": {"seed": seed}}
        results.append(evaluate(cases, merged(params, seeds), gt_flow, extra))
        print(f"seed {seed} done", file=sys.stderr)
    return results


def evaluate_mean(cases, params, gt_flow, runs):
    """The mean MRE per case over `runs` seeds ([`evaluate_seeds`]); one run is [`evaluate`]."""
    results = evaluate_seeds(cases, params, gt_flow, runs)
    return {case: sum(r[case] for r in results) / len(results) for case in results[0]}


def option(args, name, default):
    """The value after `name` in the list `args` (both are removed from it), or `default`."""
    if name not in args:
        return default
    i = args.index(name)
    value = args[i + 1]
    del args[i: i + 2]
    return value


def defaults():
    """The library's defaults, as `soup reconstruct --help` prints them."""
    text = subprocess.run([SOUP, "reconstruct", "--help"], check=True, capture_output=True, text=True).stdout
    return json.loads(text[text.index("{"): text.rindex("}") + 1])


def main():
    args = [a for a in sys.argv[1:]]
    gt_flow = "--gt-flow" in args
    only = option(args, "--only", None)
    only = set(only.split(",")) if only is not None else None
    runs = int(option(args, "--seeds", "1"))
    cases = [a for a in args if not a.startswith("--")]
    if not cases or runs < 1:
        sys.exit(__doc__)
    params = defaults()
    base = evaluate_mean(cases, {}, gt_flow, runs)
    if runs > 1:
        print(f"means over {runs} seeds")
    print("defaults: " + ", ".join(f"{c} {m:.4f}" for c, m in base.items()))
    print()
    print("| parameter | default | −20 % | +20 % | largest MRE change | on case |")
    print("| --- | --- | --- | --- | --- | --- |")
    for group in ("init", "scales", "refine", "ensemble"):
        for name, value in params[group].items():
            if name in SKIP or isinstance(value, bool) or not isinstance(value, (int, float)):
                continue
            if only and name not in only and f"{group}.{name}" not in only:
                continue
            worst = (0.0, "")
            values = []
            for factor in (0.8, 1.2):
                v = value * factor
                if isinstance(value, int):
                    v = max(1, round(v)) if value > 0 else 0
                values.append(v)
                mre = evaluate_mean(cases, {group: {name: v}}, gt_flow, runs)
                for case, m in mre.items():
                    if abs(m - base[case]) > abs(worst[0]):
                        worst = (m - base[case], case)
            print(f"| {group}.{name} | {value} | {values[0]:g} | {values[1]:g} | {worst[0]:+.4f} | {worst[1]} |", flush=True)


if __name__ == "__main__":
    main()
