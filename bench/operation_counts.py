"""Compare the operation counts of the generated functions with the recorded baseline.

``generated/operation_counts.json`` (written by ``make derive``) holds, per generated function, the
number of operations before and after common-subexpression elimination.  The baseline
``bench/operation_counts_baseline.json`` records them at a known-good state;
``tests/test_operation_counts.py`` fails when a function's count grows by more than
:data:`TOLERANCE` over it.  New functions are allowed; removed ones are reported.

Usage::

    python bench/operation_counts.py            # print the comparison
    python bench/operation_counts.py --update   # take the current counts as the new baseline

Update the baseline only when a growth is understood and wanted (say why in the commit).
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CURRENT = ROOT / "generated" / "operation_counts.json"
BASELINE = ROOT / "bench" / "operation_counts_baseline.json"
TOLERANCE = 0.05
"""Largest allowed relative growth of an operation count."""
KINDS = ("after_cse", "before_cse")


@dataclass(frozen=True)
class Comparison:
    """Result of comparing current counts with the baseline."""

    grown: list[tuple[str, str, int, int]]
    """``(module.function, kind, baseline, current)`` for counts that grew beyond the tolerance."""
    removed: list[str]
    added: list[str]
    changed: list[tuple[str, str, int, int]]
    """Every count that differs from the baseline (within tolerance or not)."""


def load_counts(path: Path) -> dict[str, dict[str, int]]:
    """``{"module.function": {"after_cse": n, "before_cse": n}}`` from an operation-counts file."""
    data = json.loads(path.read_text(encoding="utf-8"))
    counts = data["operation_counts"]
    return {
        f"{module}.{function}": dict(values)
        for module, functions in counts.items()
        for function, values in functions.items()
    }


def compare(
    baseline: dict[str, dict[str, int]], current: dict[str, dict[str, int]], tolerance: float = TOLERANCE
) -> Comparison:
    """Growth beyond ``tolerance``, removed and added functions."""
    grown, changed = [], []
    for name, base in sorted(baseline.items()):
        if name not in current:
            continue
        for kind in KINDS:
            old, new = base.get(kind), current[name].get(kind)
            if old is None or new is None or old == new:
                continue
            changed.append((name, kind, old, new))
            if new > old * (1 + tolerance):
                grown.append((name, kind, old, new))
    removed = sorted(set(baseline) - set(current))
    added = sorted(set(current) - set(baseline))
    return Comparison(grown, removed, added, changed)


def write_baseline(current_path: Path = CURRENT, baseline_path: Path = BASELINE) -> None:
    """Copy the current counts into the baseline file (with the inputs hash they came from)."""
    data = json.loads(current_path.read_text(encoding="utf-8"))
    out = {
        "source": "generated/operation_counts.json (make derive)",
        "inputs_hash": data.get("inputs_hash"),
        "operation_counts": data["operation_counts"],
    }
    baseline_path.write_text(json.dumps(out, indent=2, sort_keys=True) + "\n", encoding="utf-8")


def report(result: Comparison) -> str:
    lines = []
    for name, kind, old, new in result.changed:
        flag = "  GREW >5%" if (name, kind, old, new) in result.grown else ""
        lines.append(f"{name} {kind}: {old} -> {new} ({(new - old) / old:+.1%}){flag}")
    lines += [f"{name}: removed" for name in result.removed]
    lines += [f"{name}: new" for name in result.added]
    return "\n".join(lines) or "no change"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--update", action="store_true", help="take the current counts as the baseline")
    args = parser.parse_args(argv)
    if args.update:
        write_baseline()
        print(f"wrote {BASELINE.relative_to(ROOT)}")
        return 0
    result = compare(load_counts(BASELINE), load_counts(CURRENT))
    print(report(result))
    return 1 if result.grown else 0


if __name__ == "__main__":
    sys.exit(main())
