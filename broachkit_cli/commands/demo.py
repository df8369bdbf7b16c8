"""``broachkit demo``: the engine on two textbook problems (Bratu fold, Brusselator Hopf)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

from ..files import write_atomic, write_atomic_group, write_json
from ..options import add_json, add_out, prepare_out, print_json

NAME = "demo"
HELP = "continue the Bratu problem (fold) and the Brusselator (Hopf); write figures and data"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``broachkit demo``."""
    add_out(parser, "out/demo", "the branches and the figure")
    add_json(parser)


def _bratu_system(n: int) -> Any:
    from continuation import System

    h = 1.0 / (n + 1)

    def rhs(u: Any, p: Any, ops: Any) -> Any:
        out = []
        for i in range(n):
            left = u[i - 1] if i > 0 else 0.0
            right = u[i + 1] if i < n - 1 else 0.0
            out.append((left - 2 * u[i] + right) / h**2 + p[0] * ops.exp(u[i]))
        return ops.stack(out)

    return System(rhs, tuple(f"u{i}" for i in range(n)), ("lam",), name=f"bratu{n}")


def _brusselator() -> Any:
    from continuation import System

    def rhs(x: Any, p: Any, ops: Any) -> Any:
        a, b = p[0], p[1]
        return ops.stack([a - (b + 1) * x[0] + x[0] ** 2 * x[1], b * x[0] - x[0] ** 2 * x[1]])

    return System(rhs, ("x", "y"), ("A", "B"), name="brusselator")


def compute(out: Path) -> dict[str, Any]:
    """Run the demo continuations, save branches and figures in ``out``; return a summary."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from continuation import Event, continue_equilibria
    from continuation.plotting import plot_branch

    out.mkdir(parents=True, exist_ok=True)
    summary: dict[str, Any] = {}

    bratu = _bratu_system(50)
    br = continue_equilibria(
        bratu,
        np.zeros(50),
        {"lam": 0.0},
        "lam",
        ds=0.05,
        ds_max=0.2,
        p_min=0.0,
        p_max=4.0,
        direction="forward",
        max_steps=300,
        events=(Event("max_u_10", lambda x, p: float(np.max(x)) - 10.0, terminal=True),),
    )
    write_atomic_group(out, lambda d: br.save(d / "bratu50_branch.npz"))
    write_atomic(out / "bratu50_branch.csv", br.to_csv)
    summary["bratu50"] = {
        "status": br.status.name,
        "folds": [sp.p for sp in br.find("fold")],
        "steps": len(br),
    }

    bru = _brusselator()
    bb = continue_equilibria(
        bru,
        [1.0, 1.0],
        {"A": 1.0, "B": 1.0},
        "B",
        ds=0.05,
        p_min=0.5,
        p_max=3.0,
        direction="forward",
    )
    write_atomic_group(out, lambda d: bb.save(d / "brusselator_branch.npz"))
    write_atomic(out / "brusselator_branch.csv", bb.to_csv)
    summary["brusselator"] = {
        "status": bb.status.name,
        "hopf": [{"B": sp.p, "omega": sp.data.get("omega")} for sp in bb.find("hopf")],
        "exact_hopf_B": 2.0,
    }

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    plot_branch(axes[0], br, y=lambda x, p: float(np.max(x)))
    axes[0].set_xlabel("lambda")
    axes[0].set_ylabel("max u")
    axes[0].set_title("Bratu problem, N = 50 (fold)")
    plot_branch(axes[1], bb, y="y")
    axes[1].set_xlabel("B")
    axes[1].set_ylabel("y")
    axes[1].set_title("Brusselator, A = 1 (Hopf at B = 2)")
    fig.tight_layout()
    write_atomic(out / "demo.png", lambda p: fig.savefig(p, dpi=120))
    plt.close(fig)
    summary["figures"] = ["demo.png"]
    write_json(out / "summary.json", summary)
    return summary


def run(args: argparse.Namespace) -> int:
    """Run ``broachkit demo``."""
    out = prepare_out(args.out)
    summary = compute(out)
    if args.json:
        print_json(summary)
    else:
        for name, s in summary.items():
            sys.stdout.write(f"{name}: {s}\n")
        sys.stdout.write(f"figures and data written to {args.out}\n")
    return 0
