#!/usr/bin/python3
"""The bad-input corpus (issue 31): makes >= 1000 bad inputs for every reader and command of
moslam from small valid inputs that moslam itself writes (seeded, nothing committed), runs one
`moslam` command per case with a timeout, and classifies each outcome (classify.py). Exits 1 on
any crash, hang, nameless error or huge message; 77 (ctest's skip) when a prerequisite is absent.

  /usr/bin/python3 tools/bad_input_corpus/corpus.py --moslam build/apps/moslam/moslam          # all
  /usr/bin/python3 tools/bad_input_corpus/corpus.py --moslam build/apps/moslam/moslam --fast   # CI
  /usr/bin/python3 tools/bad_input_corpus/corpus.py --self-test   # the classifier can fail

docs/ROBUSTNESS.md describes the readers, the classes and how to add a case.
"""

import argparse
import collections
import concurrent.futures
import os
import random
import shutil
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from classify import CLASSES, FAILURES, classify, run_command  # noqa: E402

SKIP = 77


def select_fast(specs, seed, budget):
    """A seeded subset of every reader within `budget` cost units: half the budget shared by
    the readers' sizes, half equally, so that small readers are checked too; the valid cases
    always."""
    rng = random.Random(seed)
    by_reader = collections.defaultdict(list)
    for spec in specs:
        by_reader[spec.reader].append(spec)
    chosen = []
    for reader in sorted(by_reader):
        group = sorted(by_reader[reader], key=lambda s: s.name)
        rng.shuffle(group)
        group.sort(key=lambda s: not s.valid)  # stable: valid cases first, the rest shuffled
        share = budget * (0.5 * len(group) / len(specs) + 0.5 / len(by_reader))
        cost = 0
        for spec in group:
            if cost + spec.cost > share and not spec.valid:
                continue
            chosen.append(spec)
            cost += spec.cost
    return chosen


def run_case(spec, args, work):
    # A number, not the case's name: a name such as "Camera.fx_nan" in every path of the message
    # would count as the key being named.
    case_dir = os.path.join(work, "cases", spec.reader, f"{spec.number:04d}")
    os.makedirs(case_dir, exist_ok=True)
    moslam_args, names = spec.build(case_dir)
    env = dict(os.environ, OMP_WAIT_POLICY="passive", OMP_NUM_THREADS="1")
    timeout = spec.timeout or args.timeout
    start = time.monotonic()
    code, stderr = run_command([args.moslam] + moslam_args, case_dir, timeout, env)
    seconds = time.monotonic() - start
    verdict = classify(code, stderr, names)
    if spec.valid and verdict != "success":
        verdict = "valid input refused"
    if verdict in ("clean error", "success") and not args.keep:
        shutil.rmtree(case_dir, ignore_errors=True)
    return spec, verdict, code, stderr, seconds, moslam_args


def excerpt(text, n=400):
    text = text.strip().replace("\n", " | ")
    return text if len(text) <= n else text[:n] + "..."


def report(results, out, wall):
    counts = collections.Counter(v for _, v, *_ in results)
    per_reader = collections.defaultdict(collections.Counter)
    for spec, verdict, *_ in results:
        per_reader[spec.reader][verdict] += 1
    short = {"clean error": "clean", "success": "success", "crash": "crash", "hang": "hang",
             "nameless error": "nameless", "huge message": "huge", "valid input refused": "refused"}
    print(f"{'reader':<16}" + "".join(f"{short[c]:>10}" for c in CLASSES) + f"{'total':>8}",
          file=out)
    for reader in sorted(per_reader):
        row = per_reader[reader]
        print(f"{reader:<16}" + "".join(f"{row[c]:>10}" for c in CLASSES) +
              f"{sum(row.values()):>8}", file=out)
    print(f"{'all':<16}" + "".join(f"{counts[c]:>10}" for c in CLASSES) + f"{len(results):>8}",
          file=out)
    print(f"{len(results)} cases in {wall:.0f} s", file=out)
    return counts


def write_tsv(results, path):
    with open(path, "w") as f:
        f.write("reader\tcase\tfolder\tclass\texit\tseconds\tcommand\tstderr\n")
        for spec, verdict, code, stderr, seconds, moslam_args in results:
            cmd = " ".join(moslam_args).replace("\t", " ")
            f.write(f"{spec.reader}\t{spec.name}\t{spec.number:04d}\t{verdict}\t{code}\t"
                    f"{seconds:.1f}\t{cmd}\t"
                    f"{excerpt(stderr, 600)}\n")


def self_test():
    """The classifier must be able to fail: deliberately bad commands land in failure classes."""
    env = dict(os.environ)
    cases = [
        (["/bin/sh", "-c", "kill -SEGV $$"], [["x"]], "crash"),
        (["/bin/sh", "-c", "echo 'x.yaml: check failed: a' >&2; exit 2"], [["x.yaml"]], "crash"),
        (["/bin/sh", "-c", "echo 'unexpected error: x.yaml' >&2; exit 3"], [["x.yaml"]], "crash"),
        (["/bin/sh", "-c", "sleep 30"], [["x"]], "hang"),
        (["/bin/sh", "-c", "echo 'error: bad value' >&2; exit 2"], [["x.yaml"]], "nameless error"),
        (["/bin/sh", "-c", "echo 'x.yaml: bad value' >&2; exit 2"], [["x.yaml"], ["Camera.fx"]],
         "nameless error"),
        (["/bin/sh", "-c", "head -c 200000 /dev/zero | tr '\\0' a >&2; echo x.yaml >&2; exit 2"],
         [["x.yaml"]], "huge message"),
        (["/bin/sh", "-c", "echo 'x.yaml:3: key Camera.fx: bad' >&2; exit 2"],
         [["x.yaml"], ["Camera.fx"]], "clean error"),
        (["/bin/true"], [["x"]], "success"),
    ]
    wrong = 0
    for argv, names, expected in cases:
        code, stderr = run_command(argv, ".", 2, env)
        got = classify(code, stderr, names)
        ok = got == expected
        wrong += not ok
        print(f"{'ok  ' if ok else 'FAIL'} {expected:<15} got {got:<15} {' '.join(argv)[:60]}")
    print("self-test:", "passed" if not wrong else f"{wrong} misclassified")
    return 1 if wrong else 0


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--moslam", help="the moslam program (build/apps/moslam/moslam)")
    p.add_argument("--work", default="out/bad_input_corpus", help="folder for inputs and report")
    p.add_argument("--seed", type=int, default=31)
    p.add_argument("--fast", action="store_true", help="the CI subset (a few hundred cases)")
    p.add_argument("--fast-budget", type=int, default=300, help="cost units of the fast subset")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--timeout", type=float, default=60.0, help="seconds per case")
    p.add_argument("--reader", action="append", help="only these readers (repeatable)")
    p.add_argument("--match", help="only cases whose name contains this")
    p.add_argument("--keep", action="store_true", help="keep the inputs of every case")
    p.add_argument("--list", action="store_true", help="list the cases and exit")
    p.add_argument("--self-test", action="store_true", help="check the classifier and exit")
    return p.parse_args()


def main():
    args = parse_args()
    if args.self_test:
        return self_test()
    if not args.moslam or not os.access(args.moslam, os.X_OK):
        print(f"skipped: no moslam program at '{args.moslam}'")
        return SKIP
    try:
        import cv2  # noqa: F401
        import numpy  # noqa: F401
    except ImportError as e:
        print(f"skipped: {e} (Debian: apt-get install python3-opencv python3-numpy)")
        return SKIP
    import base
    import cases
    args.moslam = os.path.abspath(args.moslam)
    work = os.path.abspath(args.work)
    start = time.monotonic()
    if os.path.isdir(os.path.join(work, "cases")):
        shutil.rmtree(os.path.join(work, "cases"))
    inputs = base.make_base_inputs(args.moslam, os.path.join(work, "base"))
    specs = cases.all_specs(inputs, args.seed)
    if args.reader:
        specs = [s for s in specs if s.reader in args.reader]
    if args.match:
        specs = [s for s in specs if args.match in s.name]
    if args.fast:
        specs = select_fast(specs, args.seed, args.fast_budget)
    for number, spec in enumerate(specs):
        spec.number = number
    if args.list:
        for s in specs:
            print(f"{s.reader}\t{s.name}\tcost {s.cost}")
        print(f"{len(specs)} cases")
        return 0
    print(f"{len(specs)} cases{' (fast subset)' if args.fast else ''}, {args.jobs} jobs, "
          f"timeout {args.timeout:.0f} s; inputs under {work}", flush=True)
    results = []
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        futures = [pool.submit(run_case, s, args, work) for s in specs]
        for future in concurrent.futures.as_completed(futures):
            results.append(future.result())
            if len(results) % 100 == 0 or results[-1][1] in FAILURES:
                spec, verdict = results[-1][:2]
                print(f"{len(results)}/{len(specs)} after {time.monotonic() - start:.0f} s; "
                      f"last: {spec.reader}/{spec.name}: {verdict}", flush=True)
    results.sort(key=lambda r: (r[0].reader, r[0].name))
    write_tsv(results, os.path.join(work, "report.tsv"))
    failures = [r for r in results if r[1] in FAILURES]
    for spec, verdict, code, stderr, _, moslam_args in failures:
        print(f"{verdict.upper()}: {spec.reader}/{spec.name} (folder {spec.number:04d}, exit "
              f"{code})\n  moslam "
              f"{' '.join(moslam_args)}\n  {excerpt(stderr)}")
    report(results, sys.stdout, time.monotonic() - start)
    print(f"report: {os.path.join(work, 'report.tsv')}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
