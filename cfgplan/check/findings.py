"""What the static checker found, and the names it checks against: shared by
the checks of a domain (:mod:`cfgplan.check.checker`) and of a state and
goal (:mod:`cfgplan.check.state`)."""

from __future__ import annotations

from cfgplan.check.messages import by_position
from cfgplan.check.unify import Signature
from cfgplan.diagnostics import Diagnostic, Severity, did_you_mean
from cfgplan.ir.model import Domain, Functionality, Method, Span


class Findings:
    """Collects diagnostics while walking one domain (and state, goal); knows
    the domain's functionalities and method versions by signature."""

    def __init__(self, domain: Domain) -> None:
        self.domain = domain
        self.found: list[Diagnostic] = []
        self.funcs: dict[Signature, Functionality] = {}
        self.versions: dict[Signature, list[Method]] = {}
        for f in domain.functionalities:
            self.funcs.setdefault(f.name.signature, f)
        for m in domain.methods:
            self.versions.setdefault(m.name.signature, []).append(m)

    def report(
        self, severity: Severity, message: str, span: Span | None, hint: str | None = None
    ) -> None:
        self.found.append(Diagnostic(severity, message, span, hint))

    def sorted(self) -> list[Diagnostic]:
        """The domain's file first, then the state's (and the goal's)."""
        spans = [self.domain.span, *(x.span for x in self.domain.functionalities)]
        spans += [m.span for m in self.domain.methods]
        return by_position(self.found, [s.file for s in spans if s is not None])

    def did_you_mean(self, name: str, methods_only: bool = False) -> str | None:
        """A hint when ``name`` is likely a slip for a defined name (in case
        or spelling: :func:`cfgplan.diagnostics.did_you_mean`)."""
        names = [sig[0] for sig in self.versions]
        if not methods_only:
            names += [sig[0] for sig in self.funcs]
        return did_you_mean(name, names)
