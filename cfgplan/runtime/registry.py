"""Where the actual functions come from (5.2.1): implementations by name.

Each functionality of a configuration "has a matching functionality
implemented on a robot". Users declare one with :func:`functionality`::

    from cfgplan.runtime import functionality

    @functionality("measure-door")
    def measure_door(door: str, image: Image) -> tuple[Pos, float]:
        ...  # object arguments first, then the inputs in :in order
        return pos, orient  # the outputs in :out order

An implementation receives the object arguments (the functionality's
arguments after the robot, as the LISP call passes them) and then one value
per ``:in`` descriptor, in ``:in`` order (an implementation that cannot take
them is refused when the robot is configured, before anything runs: see
:meth:`Implementation.check`). It returns a tuple or list with one
value per ``:out`` descriptor in ``:out`` order, or the value itself when
there is one output; an action (no output) returns nothing. ``None`` in place
of an output means "no data this time": that output's channels are not
written. The robot it runs on is :func:`cfgplan.runtime.current_robot`.

An optional ``precondition`` receives the object arguments and says whether
the function may run now (5.2.1); by default it always may. An optional
``stop`` receives the object arguments when the functionality stops running
— switched out by a reconfiguration, or stopped safely when no configuration
is admissible (5.5): an action's chance to halt its motors.

:meth:`Registry.load` collects the implementations of a module given by name
(``examples.cross_door.impl``) or by path (``examples/cross-door/impl.py``).
Whatever goes wrong while importing it — a syntax error, an exception, a
``sys.exit`` — is reported as the implementation file's fault, with the file
and line, never as a traceback.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import sys
import traceback
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from cfgplan.runtime.errors import RunError, printable

__all__ = ["Implementation", "Precondition", "Registry", "functionality", "load_module"]

Precondition = Callable[..., bool]


@dataclass(frozen=True)
class Implementation:
    """The actual function of a functionality, with its precondition."""

    name: str
    function: Callable[..., object]
    precondition: Precondition | None = None
    stop: Callable[..., object] | None = None

    def __call__(self, *args: object) -> object:
        return self.function(*args)

    def allowed(self, *objects: object) -> bool:
        """Whether the precondition holds for these object arguments."""
        return True if self.precondition is None else bool(self.precondition(*objects))

    def check(self, instance: str, objects: int, inputs: int | None) -> None:
        """Refuse, before anything runs, an implementation that cannot be called
        as the functionality ``instance`` calls it: ``objects`` object
        arguments, then ``inputs`` inputs (``None``: not known, not checked);
        its ``precondition`` and ``stop`` with the object arguments alone."""
        parts: list[tuple[str, Callable[..., object] | None, int]] = [
            ("function", self.function if inputs is not None else None, objects + (inputs or 0)),
            ("precondition", self.precondition, objects),
            ("stop", self.stop, objects),
        ]
        for role, function, count in parts:
            if function is None:
                continue
            problem = _cannot_take(function, count)
            if problem is None:
                continue
            passed = f"{objects} object argument{'' if objects == 1 else 's'}"
            if role == "function":
                passed += f" then {inputs} input{'' if inputs == 1 else 's'} (in :in order)"
            file, line = _where(function)
            raise RunError(
                f"the {role} {_name(function)} declared for {self.name} cannot be called "
                f"as {instance} calls it, with {passed}: {problem}",
                hint="an implementation takes the functionality's object arguments (those "
                "after the robot), then one value per :in descriptor; its precondition and "
                "stop take the object arguments alone (docs/how-to/write-implementations.md)",
                file=file,
                line=line,
                column=None if line is None else 1,
            )


def _cannot_take(function: Callable[..., object], count: int) -> str | None:
    """Why ``function`` cannot be called with ``count`` positional arguments;
    ``None`` when it can, or when its signature cannot be read (a builtin)."""
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return None
    try:
        signature.bind(*range(count))
    except TypeError as exc:
        return str(exc)
    return None


def _name(function: Callable[..., object]) -> str:
    return printable(getattr(function, "__qualname__", None) or repr(function))


def _where(function: Callable[..., object]) -> tuple[str | None, int | None]:
    """The file and line where ``function`` is defined, when Python knows them."""
    code = getattr(inspect.unwrap(function), "__code__", None)
    if code is None:
        return None, None
    return code.co_filename, code.co_firstlineno


def functionality(
    name: str,
    *,
    precondition: Precondition | None = None,
    stop: Callable[..., object] | None = None,
) -> Callable[[Callable[..., object]], Implementation]:
    """Declare the implementation of the functionality ``name`` (a decorator)."""

    def declare(function: Callable[..., object]) -> Implementation:
        return Implementation(name, function, precondition, stop)

    return declare


class Registry:
    """Implementations by functionality name."""

    def __init__(self, implementations: Iterable[Implementation] = (), source: str = "") -> None:
        self.source = source
        self._by_name: dict[str, Implementation] = {}
        for impl in implementations:
            if impl.name in self._by_name:
                where = f" in {source}" if source else ""
                raise RunError(f"functionality {impl.name} is implemented twice{where}")
            self._by_name[impl.name] = impl

    def names(self) -> list[str]:
        return sorted(self._by_name)

    def __contains__(self, name: object) -> bool:
        return name in self._by_name

    def lookup(self, name: str) -> Implementation:
        """The implementation of ``name``; a clear error when there is none."""
        impl = self._by_name.get(name)
        if impl is None:
            self.require([name])
        assert impl is not None  # require raised
        return impl

    @classmethod
    def from_module(cls, module: ModuleType) -> Registry:
        """Every :class:`Implementation` defined at the top of ``module``."""
        found = [v for v in vars(module).values() if isinstance(v, Implementation)]
        return cls(found, source=getattr(module, "__file__", None) or module.__name__)

    @classmethod
    def load(cls, spec: str | Path) -> Registry:
        """From a module name (``pkg.impl``) or a Python file (``dir/impl.py``)."""
        text = str(spec)
        if text.endswith(".py") or "/" in text or "\\" in text:
            return cls.from_module(load_module(Path(text)))
        try:
            module = _import(text)
        except ImportError as exc:
            if exc.name is not None and text.startswith(exc.name):
                raise RunError(
                    f"cannot import implementations {text}: {exc}",
                    hint="give a module name importable from the current directory, "
                    "or the path of a .py file",
                ) from None
            raise _import_fault(text, exc) from None
        except (Exception, SystemExit) as exc:
            raise _import_fault(text, exc) from None
        return cls.from_module(module)

    def serves(self, functionalities: Iterable[tuple[str, int, int]]) -> bool:
        """Whether each functionality ``(name, objects, inputs)`` has an
        implementation that can be called with its ``objects`` object
        arguments and ``inputs`` inputs (:meth:`Implementation.check`): then
        any part made of them passes :func:`~cfgplan.runtime.install.runnable`'s
        check of implementations."""
        for name, objects, inputs in functionalities:
            impl = self._by_name.get(name)
            if impl is None:
                return False
            try:
                impl.check(name, objects, inputs)
            except RunError:
                return False
        return True

    def require(self, names: Iterable[str]) -> None:
        """Fail at once, naming every functionality without implementation."""
        missing = sorted({n for n in names if n not in self._by_name})
        if missing:
            from cfgplan.diagnostics import did_you_mean  # light: no pydantic, no planner

            where = f" in {self.source}" if self.source else ""
            hint = f'declare one with @functionality("{missing[0]}") from cfgplan.runtime'
            near = did_you_mean(missing[0], self.names())
            if near is not None:  # localize for localise: the domain's spelling is the name
                hint = f"{near} (the domain names it {missing[0]}: {hint})"
            raise RunError(
                f"no implementation of functionalit{'y' if len(missing) == 1 else 'ies'} "
                f"{', '.join(missing)}{where} (implemented: {', '.join(self.names()) or 'none'})",
                hint=hint,
            )


def _import(name: str) -> ModuleType:
    """Import ``name``, also from the current directory (which a console script
    does not put on sys.path)."""
    here = str(Path.cwd())
    if here in sys.path or "" in sys.path:
        return importlib.import_module(name)
    sys.path.insert(0, here)
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(here)


def load_module(path: Path) -> ModuleType:
    """Import a Python file by path (once per file per process)."""
    resolved = path.resolve()
    if not resolved.is_file():
        raise RunError(f"{path}: no such Python file")
    digest = hashlib.sha1(str(resolved).encode()).hexdigest()[:12]
    name = f"_cfgplan_loaded_{resolved.stem.replace('-', '_')}_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, resolved)
    if spec is None or spec.loader is None:
        raise RunError(f"{path}: cannot be loaded as a Python module")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except (Exception, SystemExit) as exc:
        del sys.modules[name]
        raise _import_fault(str(path), exc, resolved) from None
    except BaseException:
        del sys.modules[name]
        raise
    return module


def _import_fault(shown: str, exc: BaseException, path: Path | None = None) -> RunError:
    """Importing the implementations ``shown`` failed: where, and why."""
    if isinstance(exc, SyntaxError):
        file = shown if path is not None and exc.filename == str(path) else exc.filename
        return RunError(
            f"the implementations in {shown} do not compile: {printable(str(exc.msg))}",
            file=file,
            line=exc.lineno,
            column=exc.offset,
        )
    frames = traceback.extract_tb(exc.__traceback__)
    mine = [f for f in frames if path is not None and f.filename == str(path)]
    spot = mine[-1] if mine else (frames[-1] if frames else None)
    if isinstance(exc, SystemExit):
        what = f"called sys.exit({printable(repr(exc.code))})"
    else:
        what = f"raised {type(exc).__name__}: {printable(str(exc))[:200]}"
    if spot is None:
        return RunError(f"importing the implementations {shown} {what}")
    file = shown if path is not None and spot.filename == str(path) else spot.filename
    return RunError(
        f"importing the implementations {shown} {what}",
        file=file,
        line=spot.lineno,
    )
