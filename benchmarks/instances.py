"""The instances the benchmark suite plans (``python -m benchmarks.run``).

The thesis's three experiments; the ``wall`` and ``relay`` families the search
was first tuned on; and the structures it was not: ``ecology``,
``media-tight``, ``fusion``, ``chain``, ``delegation`` and ``gateway``
(:mod:`benchmarks.families`); and shared and recursive sub-derivations
``dag`` and ``conversion``. Small ones are also run by the naive baseline.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from benchmarks import families

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Instance:
    name: str
    kind: str  # "file" or the name of a generator in benchmarks.families
    args: tuple[object, ...]
    baseline: bool = True  # small enough for the naive baseline
    all_distinct: bool = True  # small enough to list every distinct configuration
    sequence: bool = False  # a sequence of goals: ranked sequences


def _file(name: str, domain: str, state: str) -> Instance:
    return Instance(name, "file", (domain, state))


def _big(name: str, kind: str, *args: object) -> Instance:
    """Too big for the baseline and for listing every configuration."""
    return Instance(name, kind, args, baseline=False, all_distinct=False)


INSTANCES = [
    _file("cross-door 6.2.2", "cross-door/domain.lisp", "cross-door/state-6.2.2-step1.lisp"),
    _file("carry-bar 6.3.2", "carry-bar/domain.lisp", "carry-bar/state-6.3.2.lisp"),
    _file("build-wall 6.4", "build-wall/domain.lisp", "build-wall/state-6.4.lisp"),
    Instance("wall K=3 N=4 L=3", "wall", (3, 4, 3)),
    Instance("wall K=4 N=6 L=4", "wall", (4, 6, 4)),
    _big("wall K=6 N=20 L=8", "wall", 6, 20, 8),
    _big("wall K=8 N=50 L=20", "wall", 8, 50, 20),
    Instance("relay D=4 W=4 V=3", "relay", (4, 4, 3)),
    Instance("relay D=5 W=5 V=3", "relay", (5, 5, 3), baseline=False),
    _big("relay D=8 W=10 V=4", "relay", 8, 10, 4),
    Instance("ecology N=6 R=2 C=1", "ecology", (6, 2, 1)),
    _big("ecology N=18 R=3 C=3", "ecology", 18, 3, 3),
    _big("ecology N=50 R=5 C=5", "ecology", 50, 5, 5),
    Instance("media-tight N=4 R=2 C=1", "media_tight", (4, 2, 1)),
    _big("media-tight N=8 R=3 C=2", "media_tight", 8, 3, 2),
    _big("media-tight N=15 R=4 C=4", "media_tight", 15, 4, 4),
    Instance("fusion M=4 V=3 P=4 H=3", "fusion", (4, 3, 4, 3)),
    _big("fusion M=14 V=3 P=6 H=6", "fusion", 14, 3, 6, 6),
    _big("fusion M=30 V=3 P=6 H=6", "fusion", 30, 3, 6, 6),
    _big("fusion M=60 V=3 P=6 H=6", "fusion", 60, 3, 6, 6),  # the CP-SAT comparison planner: 2.0 s
    Instance("chain D=8", "chain", (8,)),
    _big("chain D=30", "chain", 30),
    _big("chain D=100", "chain", 100),
    _big("chain D=150", "chain", 150),
    _big("chain D=200", "chain", 200),
    Instance("delegation N=4", "delegation", (4,)),
    Instance("delegation N=5", "delegation", (5,), baseline=False),
    Instance("delegation N=6", "delegation", (6,), baseline=False),
    # Shared and recursive sub-derivations (benchmarks/families/shared.py).
    # The CP-SAT anchor, process start to exit: dag D=18 0.9 s, D=24 2.2 s,
    # D=30 2.3 s; conversion D=28 0.8 s, D=40 1.3 s.
    Instance("dag D=5", "dag", (5,)),
    _big("dag D=12", "dag", 12),
    _big("dag D=16", "dag", 16),
    _big("dag D=18", "dag", 18),
    _big("dag D=24", "dag", 24),
    _big("dag D=30", "dag", 30),
    Instance("conversion D=4", "conversion", (4,)),
    _big("conversion D=12", "conversion", 12),
    _big("conversion D=20", "conversion", 20),
    _big("conversion D=28", "conversion", 28),
    _big("conversion D=40", "conversion", 40),
    Instance("gateway N=4 D=4", "gateway", (4, 4)),
    _big("gateway N=8 D=8", "gateway", 8, 8),
    _big("gateway N=8 D=5", "gateway", 8, 5),
    _big("gateway N=20 D=20", "gateway", 20, 20),
    Instance("deliveries S=2 R=3", "deliveries", (2, 3), False, False, sequence=True),
    Instance("deliveries S=5 R=3", "deliveries", (5, 3), False, False, sequence=True),
    Instance("deliveries S=10 R=3", "deliveries", (10, 3), False, False, sequence=True),
]


def by_name(name: str) -> Instance:
    """The instance of :data:`INSTANCES` named ``name`` (exit with a message
    when there is none)."""
    for instance in INSTANCES:
        if instance.name == name:
            return instance
    raise SystemExit(f"no benchmark instance named {name!r}")


def problem_files(instance: Instance, folder: Path) -> tuple[Path, Path]:
    """The domain and state files of an instance (generated ones into ``folder``)."""
    if instance.kind == "file":
        domain, state = instance.args
        return ROOT / "domains" / str(domain), ROOT / "domains" / str(state)
    make = getattr(families, instance.kind)
    domain_text, state_text = make(*instance.args)
    (folder / "domain.lisp").write_text(domain_text)
    (folder / "state.lisp").write_text(state_text)
    return folder / "domain.lisp", folder / "state.lisp"
