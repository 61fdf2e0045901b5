"""Regenerate every module in ``generated/``: ``python -m derive [--out DIR] [--check]``."""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
import time
from pathlib import Path

from derive import codegen, extras, kernels

LOG = logging.getLogger("derive")

#: Derivation modules, in emission order.  Each has ``build() -> GeneratedModule``.
DERIVATIONS = (
    "derive.pendulum",
    "derive.rider_model",
    "derive.combination",
    "derive.measured_reduction",
    "derive.benchmark_model",
    "derive.gap_effects",
    "derive.state_space",
    "derive.sensitivities",
)

GENERATOR = "python -m derive"
PROJECT_ROOT = Path(__file__).resolve().parent.parent


def generate(out_dir: Path) -> dict[str, dict[str, tuple[int, int]]]:
    """Write every generated module into ``out_dir``; return the operation counts."""
    digest = codegen.inputs_hash()
    counts: dict[str, dict[str, tuple[int, int]]] = {}
    out_dir.mkdir(parents=True, exist_ok=True)
    modules = []
    for dotted in DERIVATIONS:
        start = time.perf_counter()
        module = importlib.import_module(dotted).build()
        text, module_counts = codegen.render_module(module, GENERATOR, digest)
        written = codegen.write_if_changed(out_dir / f"{module.name}.py", text)
        counts[module.name] = module_counts
        modules.append(module)
        LOG.info("%s: %s in %.1f s", module.name, "written" if written else "unchanged", time.perf_counter() - start)
    # Fused C kernels from the same expressions (not a NumPy module; the manifest lists them too).
    text, counts[kernels.MODULE] = kernels.render(GENERATOR, digest)
    codegen.write_if_changed(out_dir / f"{kernels.MODULE}.py", text)
    extra = extras.build(digest, GENERATOR, counts, modules, kernels.manifest_entries())
    for filename, text in extra.items():
        codegen.write_if_changed(out_dir / filename, text)
    return counts


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m derive", description=__doc__)
    parser.add_argument("--out", type=Path, default=PROJECT_ROOT / "generated", help="output folder")
    parser.add_argument("-q", "--quiet", action="store_true", help="log warnings only")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING if args.quiet else logging.INFO, format="%(name)s: %(message)s")
    start = time.perf_counter()
    counts = generate(args.out)
    total = sum(after for module in counts.values() for _, after in module.values())
    LOG.info(
        "generated %d modules (%d operations after CSE) in %.1f s", len(counts), total, time.perf_counter() - start
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
