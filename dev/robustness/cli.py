"""The probe's command: run the catalogue, write probe.json and probe.md, print progress."""

from __future__ import annotations

import argparse
import json
import os
from collections import Counter
from collections.abc import Sequence

from benchmarks.core.machine import machine_info
from dev.robustness.api_cases import api_probes
from dev.robustness.cli_cases import cli_probes
from dev.robustness.close_cases import close_probes
from dev.robustness.interrupt_cases import interrupt_probes
from dev.robustness.probe import Probe
from dev.robustness.runner import run_probes
from dev.robustness.solver_cases import solver_probes
from dev.robustness.store_cases import store_probes
from dev.robustness.sweep_cases import sweep_probes
from dev.robustness.verdicts import VERDICTS, Outcome


def markdown(results: list[tuple[Probe, Outcome]]) -> str:
    """Counts per verdict (API, CLI, all) and every input that is not ``clear``, worst first."""
    lines = [
        "# Bad and edge inputs",
        "",
        "| door | " + " | ".join(VERDICTS) + " | total |",
        "|---|" + "---:|" * (len(VERDICTS) + 1),
    ]
    for door in ("api", "cli", "all"):
        chosen = [o for p, o in results if door in ("all", p.group)]
        counts = Counter(o.verdict for o in chosen)
        lines.append(
            f"| {door} | " + " | ".join(str(counts.get(v, 0)) for v in VERDICTS) + f" | {len(chosen)} |"
        )
    lines += [
        "",
        "## Inputs that are not clear",
        "",
        "| verdict | input | s | what happened |",
        "|---|---|---:|---|",
    ]
    order = {v: k for k, v in enumerate(reversed(VERDICTS))}
    for probe, outcome in sorted(results, key=lambda r: (order[r[1].verdict], r[0].id)):
        if outcome.verdict == "clear":
            continue
        detail = outcome.detail.replace("|", "\\|").replace("\n", " ")
        lines.append(f"| {outcome.verdict} | `{probe.id}` | {outcome.elapsed:.1f} | {detail} |")
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Run the probes; exit 0 when every input got a clear answer, 1 otherwise."""
    parser = argparse.ArgumentParser(prog="python -m dev.robustness", description=__doc__)
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory")
    parser.add_argument(
        "--timeout", type=float, default=30.0, help="seconds before an input counts as a hang"
    )
    parser.add_argument("--only", choices=("api", "cli"), default=None, help="one door only")
    parser.add_argument("--match", default=None, help="only the inputs whose id contains this text")
    args = parser.parse_args(argv)
    probes = [
        p
        for p in (api_probes() + solver_probes() + cli_probes() + store_probes() + interrupt_probes()
                  + sweep_probes() + close_probes())
        if (args.only in (None, p.group)) and (args.match is None or args.match in p.id)
    ]
    os.makedirs(args.out, exist_ok=True)
    total = len(probes)
    done: list[tuple[Probe, Outcome]] = []

    def report(probe: Probe, outcome: Outcome) -> None:
        done.append((probe, outcome))
        print(f"[{len(done)}/{total}] {outcome.verdict:8s} {probe.id} ({outcome.elapsed:.1f} s)", flush=True)
        _write(args.out, done)

    run_probes(probes, args.timeout, report)
    _write(args.out, done)
    return 0 if all(o.verdict == "clear" for _, o in done) else 1


def _write(out: str, results: list[tuple[Probe, Outcome]]) -> None:
    records = [
        {
            "id": p.id,
            "group": p.group,
            "kind": p.kind,
            "expect": p.expect,
            "verdict": o.verdict,
            "elapsed_s": round(o.elapsed, 3),
            "detail": o.detail,
        }
        for p, o in results
    ]
    with open(os.path.join(out, "probe.json"), "w") as handle:
        json.dump({"machine": machine_info(), "records": records}, handle, indent=1)
    with open(os.path.join(out, "probe.md"), "w") as handle:
        handle.write(markdown(results))
