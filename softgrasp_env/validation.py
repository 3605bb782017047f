"""The one validator: every config field and every ``gym.make`` argument is checked by these few
functions, so a bad value always gets the same kind of message - the name, what was wanted and
what came - and is never clamped silently.

``owner`` prefixes the name (``SceneConfig.cylinder_mass``); without it the bare name is a
``gym.make`` argument (``yaw_range``).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np


def _label(owner: str | None, name: str) -> str:
    return f"{owner}.{name}" if owner else name


def is_real(value: Any) -> bool:
    """A real number (Python's or numpy's), not a bool."""
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def check_range(name: str, value: Any, lo: float, hi: float, *, lo_open: bool = False, hi_open: bool = False,
                owner: str | None = None) -> float:  # fmt: skip
    """``value`` as a float if it is a finite number with lo <(=) value <(=) hi, else ValueError
    naming the field and the range."""
    label = _label(owner, name)
    if not is_real(value) or not math.isfinite(value):
        raise ValueError(f"{label} must be a finite number, got {value!r}")
    below = value <= lo if lo_open else value < lo
    above = value >= hi if hi_open else value > hi
    if below or above:
        left, right = "(" if lo_open else "[", ")" if hi_open else "]"
        raise ValueError(f"{label} must be in {left}{lo}, {hi}{right}, got {value!r}")
    return float(value)


def check_int(name: str, value: Any, lo: int, hi: int, *, owner: str | None = None) -> int:
    """``value`` if it is an integer in [lo, hi], else ValueError naming the field."""
    label = _label(owner, name)
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{label} must be an integer, got {value!r}")
    if not lo <= value <= hi:
        raise ValueError(f"{label} must be in [{lo}, {hi}], got {value!r}")
    return int(value)


def check_choice(name: str, value: Any, choices: Iterable[Any], *, owner: str | None = None) -> Any:
    """``value`` if it is one of ``choices``, else ValueError listing them."""
    choices = tuple(choices)
    if not any(value == c and type(value) is type(c) for c in choices):
        raise ValueError(f"{_label(owner, name)} must be one of {choices}, got {value!r}")
    return value


def check_bool(name: str, value: Any, *, owner: str | None = None, hint: str = "") -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{_label(owner, name)} must be a bool{hint}, got {value!r}")
    return bool(value)


def check_type(name: str, value: Any, cls: type | tuple[type, ...], *, owner: str | None = None) -> Any:
    if not isinstance(value, cls):
        want = cls.__name__ if isinstance(cls, type) else " or ".join(c.__name__ for c in cls)
        raise ValueError(f"{_label(owner, name)} must be a {want}, got {type(value).__name__}")
    return value


def deprecated(old: str, new: str, *, stacklevel: int = 3) -> None:
    """Warn that ``old`` is spelled ``new`` now (the old spelling keeps working)."""
    warnings.warn(f"{old} is deprecated, use {new}", DeprecationWarning, stacklevel=stacklevel)


def retired_choice(kwargs: dict, name: str, *, kept: Any, gone: Iterable[Any], release: str, owner: str | None = None,
                   stacklevel: int = 4) -> None:  # fmt: skip
    """A keyword removed because only one of its choices is left: ``kwargs[name] == kept`` is
    dropped from ``kwargs`` with a DeprecationWarning (it is what happens anyway); a value in
    ``gone`` is a ValueError naming ``release``, the last release that has it; anything else a
    ValueError naming the field. Nothing happens if ``name`` is not in ``kwargs``."""
    if name not in kwargs:
        return
    value, label = kwargs[name], _label(owner, name)
    if any(value == v and type(value) is type(v) for v in (kept,)):
        del kwargs[name]
        warnings.warn(f"{label}={kept!r} is deprecated: it is the only choice left, give no {name}", DeprecationWarning,
                      stacklevel=stacklevel)  # fmt: skip
        return
    if any(value == v and type(value) is type(v) for v in gone):
        raise ValueError(f"{label}={value!r} was retired; `pip install softgrasp-env=={release}` (git tag v{release}) "
                         f"has it. This release has only {label}={kept!r}, the default: give no {name}")  # fmt: skip
    raise ValueError(f"{label} is no longer an argument (only {kept!r} is left), got {value!r}")


def accept_old_names(cls: type, renames: dict[str, str], *, translate: Callable[[dict], dict] | None = None) -> type:
    """Let a frozen dataclass take renamed fields by their old names: ``cls(old=v)`` means
    ``cls(new=v)`` with a DeprecationWarning, and ``obj.old`` reads ``obj.new`` (warned too).
    ``translate`` may rewrite the keyword arguments further (fields that moved into a sub-config).
    ``dataclasses.replace`` keeps working: it passes the real fields only."""
    init = cls.__init__

    def __init__(self, *args, **kwargs):
        for old, new in renames.items():
            if old in kwargs:
                if new in kwargs:
                    raise TypeError(f"{cls.__name__}: give {new}= (the new name of {old}=), not both")
                deprecated(f"{cls.__name__}({old}=...)", f"{cls.__name__}({new}=...)")
                kwargs[new] = kwargs.pop(old)
        if translate is not None:
            kwargs = translate(kwargs)
        init(self, *args, **kwargs)

    __init__.__doc__ = init.__doc__
    __init__.__wrapped__ = init  # inspect.signature shows the real fields
    cls.__init__ = __init__
    for old, new in renames.items():

        def read(self, _old=old, _new=new):
            deprecated(f"{cls.__name__}.{_old}", f"{cls.__name__}.{_new}")
            return getattr(self, _new)

        setattr(cls, old, property(read, doc=f"Deprecated name of ``{new}``."))
    return cls


__all__ = ["accept_old_names", "check_bool", "check_choice", "check_int", "check_range", "check_type", "deprecated",
           "is_real", "retired_choice"]  # fmt: skip
