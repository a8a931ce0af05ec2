"""Resuming a recording: only the same plan, at the same rate, from the same device, may continue a file.

An acquisition writes into the recording's header what it records (``plan_hash``: the rod, the holds in
order, hold time, rate and settle rule), how fast (``sample_rate_Hz``) and from what (``device``: the port,
``device_hash``: the port, protocol and channel wiring). A re-run into a file that already holds samples
continues it only when all of these match; anything else is refused with what to do (``--new-file``, which
records into the next free name beside it, or another ``-o``), so two plans are never mixed in one file.
"""
from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .config import RigPlan, RigProfile
from .errors import RigError
from .recording import read_header, read_recording

__all__ = ["ResumePoint", "plan_hash", "device_hash", "identity_meta", "resume_point", "next_free_name"]

_DONE = re.compile(r"^# hold (\d+)/(\d+) complete: step (\d+)")
_ZERO = re.compile(r"^# zero (\S+): (.+)$")


def _digest(obj) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:16]


def _plan_identity(plan: RigPlan) -> dict:
    """What a plan records, by key: rod, holds in order, hold time, rate, settle rule, gauges read."""
    pr = plan.schedule
    return {"rod": plan.rod, "holds": [[a.value, r, str(ph), m] for a, r, ph, m in pr.holds()],
            "hold_s": pr.hold_s, "rate_Hz": pr.rate_Hz,
            "measured": {k: list(plan.recorded(k)) for k in sorted(pr.measured)},     # what is recorded
            "settle": [plan.settle_window_s, plan.settle_tolerance_mm, plan.settle_timeout_s]}


def _device_identity(profile: RigProfile) -> dict:
    """The wiring, by key: port, protocol, and each channel's index, axis, sign and scale (a profile of several
    instruments: each one's name, port, protocol and its settings, channels; the loader is not wiring)."""
    if hasattr(profile, "instruments"):
        return {"instruments": [i.identity() for i in profile.instruments]}
    return {"port": profile.port, "protocol": profile.protocol,
            "channels": [[c.index, c.axis, c.sign, c.scale_mm] for c in profile.channels],
            "temperature": profile.temperature_index}


def plan_hash(plan: RigPlan) -> str:
    """16 hex digits of what a plan records (:func:`_plan_identity`)."""
    return _digest(_plan_identity(plan))


def device_hash(profile: RigProfile) -> str:
    """16 hex digits of the wiring (:func:`_device_identity`)."""
    return _digest(_device_identity(profile))


def _fields(identity: dict) -> str:
    """One header value naming each part of an identity: a number or short name as it is, anything longer by
    6 hex digits of its digest (``rod=rod1 hold_s=8 holds=3f2a1c ...``), so a refused resume can say which
    part changed."""
    parts = []
    for key, value in identity.items():
        if isinstance(value, list) and value and isinstance(value[0], list) and key != "settle":
            for k, item in enumerate(value):            # one entry per hold, channel or instrument
                parts.append(f"{key}[{k}]={_digest(item)[:6]}")
            parts.append(f"{key}.count={len(value)}")
            continue
        text = json.dumps(value, sort_keys=True, separators=(",", ":"))
        parts.append(f"{key}={text if len(text) <= 24 and ' ' not in text else _digest(value)[:6]}")
    return " ".join(parts)


def identity_meta(profile: RigProfile, plan: RigPlan) -> dict:
    """The header entries a resume is checked against (the hashes decide; the fields name what changed)."""
    return {"sample_rate_Hz": f"{plan.schedule.rate_Hz:g}", "plan_hash": plan_hash(plan), "device": profile.port,
            "device_hash": device_hash(profile), "plan_fields": _fields(_plan_identity(plan)),
            "device_fields": _fields(_device_identity(profile))}


def _changed(recorded: str | None, expected: str) -> str:
    """`` (changed: hold_s 8 -> 5, holds from the 2nd on, holds.count 10 -> 8)`` from two ``*_fields`` header
    values; empty where the file has none."""
    if not recorded:
        return ""
    old = dict(p.split("=", 1) for p in recorded.split() if "=" in p)
    new = dict(p.split("=", 1) for p in expected.split() if "=" in p)
    keys = [k for k in dict.fromkeys([*old, *new]) if old.get(k) != new.get(k)]
    said = [f"{k} {old[k]} -> {new[k]}" for k in keys if "[" not in k and k in old and k in new
            and not _is_digest(old[k])]
    said += [k for k in keys if "[" not in k and k in old and k in new and _is_digest(old[k])]
    items: dict[str, list[int]] = {}
    for k in keys:
        if "[" in k:
            items.setdefault(k[:k.index("[")], []).append(int(k[k.index("[") + 1:-1]))
    said += [f"{base} {_ordinals(idx)}" for base, idx in items.items()]
    return f" (changed: {', '.join(said)})" if said else ""


def _ordinals(index: list[int]) -> str:
    """[1, 2, 3, 4] -> 'from number 2 on'; [0, 4] -> 'number 1, 5' (counted from 1)."""
    if len(index) > 3 and index == list(range(index[0], index[0] + len(index))):
        n = index[0] + 1
        return f"from number {n} on"
    return "number " + ", ".join(str(i + 1) for i in index)


def _is_digest(value: str) -> bool:
    return re.fullmatch(r"[0-9a-f]{6}", value) is not None


@dataclass
class ResumePoint:
    """Where an acquisition into a file starts.

    Attributes
    ----------
    holds_done : holds already complete in the file (0 for a new file); holds_total : holds in the plan
    last_step : last step number in the file; last_time_s : last sample time [s] (-1 without samples)
    zeros : per load axis, the zero reading [mm] of its series, shape=(3,)
    """

    holds_done: int
    holds_total: int
    last_step: int = 0
    last_time_s: float = -1.0
    zeros: dict | None = None

    @property
    def complete(self) -> bool:
        return self.holds_done >= self.holds_total

    @property
    def resuming(self) -> bool:
        return 0 < self.holds_done < self.holds_total


def _check_identity(path: Path, recorded: dict, expected: dict) -> None:
    """Refuse a resume whose plan, rate or device differs from the file's."""
    what = {"sample_rate_Hz": "sample rate [Hz]", "device": "device port", "device_hash": "device wiring (protocol, "
            "channels)", "plan_hash": "plan (rod, holds, hold time, settle rule)"}
    fix = ("rodlab never mixes two recordings in one file: record into a new file beside it with --new-file, or "
           "choose another -o; to continue this one, re-run it with the plan, rate and profile it was started with")
    for key, label in what.items():
        if key not in recorded:
            raise RigError(f"this recording has no `{key}` in its header (written by another program or an older "
                           f"rodlab), so a resume cannot be checked against it; {fix}", path=path, key=key)
        if recorded[key] != expected[key]:
            fields = key.replace("_hash", "_fields")
            changed = _changed(recorded.get(fields), expected[fields]) if fields in expected else ""
            raise RigError(f"the recording was started with another {label}{changed}: {recorded[key]!r} in the file, "
                           f"{expected[key]!r} now; {fix}", path=path, key=key)


def resume_point(path: str | Path, profile: RigProfile, plan: RigPlan) -> ResumePoint:
    """Where an acquisition of ``plan`` into ``path`` starts; refuses a file of another plan, rate or device."""
    path = Path(path)
    total = len(plan.schedule.holds())
    if not path.exists() or path.stat().st_size == 0:
        return ResumePoint(0, total, zeros={})
    text = path.read_text(encoding="utf-8", errors="replace")
    _check_identity(path, read_header(text), identity_meta(profile, plan))
    complete = text[:text.rfind("\n") + 1]            # a line cut off at the end is dropped by the writer
    done, zeros = 0, {}
    for line in complete.splitlines():                # not that line: "complete: step 1" of a torn "step 12"
        m = _DONE.match(line)
        if m:
            done = int(m.group(1))
        z = _ZERO.match(line)
        if z:
            zeros[z.group(1)] = np.array([float(v) for v in z.group(2).split(",")])
    point = ResumePoint(done, total, zeros=zeros)
    if any(ln.strip() and ln[0].isdigit() for ln in complete.splitlines()):
        rec = read_recording(path, complete)
        point.last_step, point.last_time_s = int(rec.step.max()), float(rec.time_s.max())
    return point


def next_free_name(path: str | Path) -> Path:
    """``run.rig.csv`` -> the first of ``run-2.rig.csv``, ``run-3.rig.csv``, ... that does not exist."""
    path = Path(path)
    name = path.name
    stem, ext = (name[: -len(".rig.csv")], ".rig.csv") if name.endswith(".rig.csv") else (path.stem, path.suffix)
    k = 2
    while (candidate := path.with_name(f"{stem}-{k}{ext}")).exists():
        k += 1
    return candidate
