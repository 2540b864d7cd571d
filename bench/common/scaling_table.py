#!/usr/bin/env python3
"""Scaling tables from `weft bench --json` results (bench/run_scaling_benchmarks.sh).

    scaling_table.py strong FILE.json...   one row per (scene, GPUs): ms per frame, speed-up and
                                           parallel efficiency against the same scene on 1 GPU
    scaling_table.py weak FILE.json...     one row per run: triangles per GPU, ms per frame, and the
                                           ratio to the 1-GPU run of the series

FILE.json@G takes only the runs of FILE on G GPUs. Medians of the timed frames. Markdown on stdout.
"""
import json
import sys


def runs(files):
    out = []
    for f in files:
        f, _, only = f.partition("@")
        try:
            with open(f) as stream:
                out.extend(r for r in json.load(stream) if not only or r.get("gpus") == int(only))
        except (OSError, ValueError) as e:
            print(f"<!-- {f}: {e} -->")
    return out


def fields(r):
    col = r.get("collisions", {})
    return {
        "scene": r["scene"], "gpus": r["gpus"], "triangles": r["triangles"],
        "ms": r["stage_ms"]["step"]["median"], "solve": r["stage_ms"]["solve"]["median"],
        "detect": sum(r["stage_ms"][k]["median"] for k in ("broad_phase", "culling", "narrow_phase")),
        "cg": r["cg_iterations"]["median"], "contacts": col.get("contacts", {}).get("median", 0),
        "busiest": col.get("contacts_largest_part", {}).get("median", 0),
        "memory": r.get("memory_bytes", 0), "device": r.get("device", ""),
    }


def strong(rs):
    print("| scene | triangles | GPUs | ms per frame | speed-up | efficiency | solve | detection | CG it. per frame | contacts (busiest GPU) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    base = {}
    for r in rs:
        if r["gpus"] == 1:
            base[(r["scene"], r["triangles"])] = r["ms"]
    for r in rs:
        one = base.get((r["scene"], r["triangles"]))
        up = one / r["ms"] if one else float("nan")
        share = f" ({r['busiest']:.0f})" if r["busiest"] else ""
        print(f"| {r['scene']} | {r['triangles']} | {r['gpus']} | {r['ms']:.1f} | {up:.2f}× | {100 * up / r['gpus']:.0f}% | "
              f"{r['solve']:.1f} | {r['detect']:.1f} | {r['cg']:.0f} | {r['contacts']:.0f}{share} |")


def weak(rs):
    print("| GPUs | triangles | per GPU | ms per frame | against 1 GPU | solve | detection | CG it. per frame | contacts (busiest GPU) |")
    print("|---|---|---|---|---|---|---|---|---|")
    one = next((r["ms"] for r in rs if r["gpus"] == 1), None)
    for r in sorted(rs, key=lambda r: r["gpus"]):
        ratio = r["ms"] / one if one else float("nan")
        share = f" ({r['busiest']:.0f})" if r["busiest"] else ""
        print(f"| {r['gpus']} | {r['triangles']} | {r['triangles'] // r['gpus']} | {r['ms']:.1f} | {ratio:.2f}× | "
              f"{r['solve']:.1f} | {r['detect']:.1f} | {r['cg']:.0f} | {r['contacts']:.0f}{share} |")


def main():
    if len(sys.argv) < 3 or sys.argv[1] not in ("strong", "weak"):
        print(__doc__, file=sys.stderr)
        return 2
    rs = [fields(r) for r in runs(sys.argv[2:])]
    if rs:
        print(f"<!-- {rs[0]['device']} -->")
    (strong if sys.argv[1] == "strong" else weak)(rs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
