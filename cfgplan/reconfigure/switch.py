"""From one configuration to the next with the least disruption (5.5, 7.2).

Labels are the planner's (4.5: fresh per expansion), so the same
functionality instance has different labels in two configurations — in the
cross-door example ``measure-robot-pos(Pippi, Emil)`` is F14 in the cost-44
configuration and F18 in the cost-47 one. What identifies an instance across
configurations is its name and arguments (``Configuration.identity``);
a channel is identified by its kind, the instances at its ends and its data.

:func:`relabel` gives a new configuration the labels of the running one:
an instance present in both keeps its running label, every other instance
gets a fresh label never used before in the run (so a message still in
flight on a channel that was stopped can never land on a new one). After
that, instances and channels present in both configurations have the same
labels and channel keys, and :func:`change` splits both into what is kept
(it keeps running, with its state: a channel's last value, a
functionality's schedule and memory), what is stopped and what is started.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance
from cfgplan.notation import call_text

__all__ = ["Change", "change", "channel_name", "label_number", "relabel"]

_LABEL = re.compile(r"^F(\d+)$")


def label_number(label: str) -> int:
    """``F17`` -> 17 (0 for a label of another form)."""
    found = _LABEL.match(label)
    return int(found.group(1)) if found else 0


def highest_label(configs: Iterable[Configuration | None]) -> int:
    """The highest label number among ``configs``."""
    return max(
        (label_number(f.label) for c in configs if c is not None for f in c.functionalities),
        default=0,
    )


def relabel(new: Configuration, old: Configuration | None, next_free: int) -> Configuration:
    """``new`` with the labels of ``old`` for the instances they share and
    fresh labels from ``F{next_free}`` on for the others (in ``new``'s order)."""
    running = {} if old is None else {f.key: f.label for f in old.functionalities}
    mapping: dict[str, str] = {}
    number = next_free
    for f in new.functionalities:
        if f.key in running:
            mapping[f.label] = running[f.key]
        else:
            mapping[f.label] = f"F{number}"
            number += 1
    functionalities = tuple(
        f.model_copy(update={"label": mapping[f.label]}) for f in new.functionalities
    )
    channels = tuple(
        c.model_copy(update={"source": mapping[c.source], "target": mapping[c.target]})
        for c in new.channels
    )
    return new.model_copy(update={"functionalities": functionalities, "channels": channels})


def channel_identity(c: Channel) -> tuple[object, ...]:
    """What a channel is, apart from its bandwidth: kind, ends, data."""
    return (c.kind, c.source, c.target, c.data)


def channel_name(c: Channel) -> str:
    """``F7->F3 pos(Emil, Door1)``: a channel in a switch report."""
    return f"{c.source}->{c.target} {call_text(c.data)}"


def instance_name(f: FunctionalityInstance) -> str:
    """``F10: compass(Emil)``."""
    return f"{f.label}: {call_text(f.key)}"


@dataclass(frozen=True)
class Change:
    """What a switch keeps running, stops and starts (labels of the relabelled
    new configuration for kept and started parts, of the old one for stopped)."""

    kept: tuple[FunctionalityInstance, ...]
    stopped: tuple[FunctionalityInstance, ...]
    started: tuple[FunctionalityInstance, ...]
    kept_channels: tuple[Channel, ...]
    stopped_channels: tuple[Channel, ...]
    started_channels: tuple[Channel, ...]

    @property
    def empty(self) -> bool:
        """Nothing stopped or started: the same configuration."""
        return not (self.stopped or self.started or self.stopped_channels or self.started_channels)

    def record(self) -> dict[str, dict[str, list[str]]]:
        """The ``kept``/``stopped``/``started`` fields of a ``switch`` trace event."""

        def part(
            fs: tuple[FunctionalityInstance, ...], cs: tuple[Channel, ...]
        ) -> dict[str, list[str]]:
            return {
                "functionalities": [instance_name(f) for f in fs],
                "channels": [channel_name(c) for c in cs],
            }

        return {
            "kept": part(self.kept, self.kept_channels),
            "stopped": part(self.stopped, self.stopped_channels),
            "started": part(self.started, self.started_channels),
        }


def change(old: Configuration | None, new: Configuration | None) -> Change:
    """Split two configurations (``new`` relabelled by :func:`relabel`) into
    kept, stopped and started parts; ``None`` is the empty configuration."""
    old_f = () if old is None else old.functionalities
    new_f = () if new is None else new.functionalities
    old_c = () if old is None else old.channels
    new_c = () if new is None else new.channels
    before = {f.key for f in old_f}
    after = {f.key for f in new_f}
    channels_before = {channel_identity(c) for c in old_c}
    channels_after = {channel_identity(c) for c in new_c}
    return Change(
        kept=tuple(f for f in new_f if f.key in before),
        stopped=tuple(f for f in old_f if f.key not in after),
        started=tuple(f for f in new_f if f.key not in before),
        kept_channels=tuple(c for c in new_c if channel_identity(c) in channels_before),
        stopped_channels=tuple(c for c in old_c if channel_identity(c) not in channels_after),
        started_channels=tuple(c for c in new_c if channel_identity(c) not in channels_before),
    )
