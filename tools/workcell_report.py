#!/usr/bin/env python3
"""Prints the verification table of docs/workcells.md from `leeway check --json` (stdlib only).

Usage: tools/workcell_report.py [path/to/leeway]   (default: build/leeway)
"""
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
LEEWAY = sys.argv[1] if len(sys.argv) > 1 else str(ROOT / "build" / "leeway")


def main() -> int:
    print("| cell, key | tool0 to goal site (mm) | clearance (m) | closest pair |")
    print("|---|---|---|---|")
    for cell in ("dallara", "baltico", "dlr"):
        path = ROOT / "mjcf" / "workcells" / f"{cell}.xml"
        out = subprocess.run([LEEWAY, "check", "--json", str(path)], capture_output=True, text=True)
        if out.returncode != 0:
            print(f"{cell}: leeway check exited {out.returncode}: {out.stdout}{out.stderr}", file=sys.stderr)
            return 1
        report = json.loads(out.stdout)
        sites = {g["site"]: g["position"] for g in report["goals"]}
        for key in report["keyframes"]:
            name = key["name"]
            if name in sites:
                err = sum((a - b) ** 2 for a, b in zip(key["tool_position"], sites[name])) ** 0.5
                err_text = f"{err * 1000:.3f}"
            else:
                err_text = "-"
            c = key["clearance"]
            print(f"| {cell.capitalize() if cell != 'dlr' else 'DLR'} {name} | {err_text} | "
                  f"{c['distance']:.3f} | {c['link']} / {c['obstacle']} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
