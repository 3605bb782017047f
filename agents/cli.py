"""Command-line pieces shared by train.py (SB3) and agents.rllib_train (RLlib)."""

from __future__ import annotations

import argparse
import ast
import json
from typing import Any


def parse_kwarg(item: str) -> tuple[str, Any]:
    """``key=value`` -> (key, value): the value as a Python literal (``0.2``, ``False``,
    ``(0.05, 0.08)``, ``'segmented'``), else the text itself (``fingers=segmented``)."""
    key, sep, text = item.partition("=")
    key = key.strip()
    if not sep or not key.isidentifier():
        raise argparse.ArgumentTypeError(f"expected key=value with key a Python name, got {item!r}")
    try:
        value = ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        value = text
    return key, value


def kwargs_dict(parser: argparse.ArgumentParser, flag: str, pairs: list[tuple[str, Any]] | None) -> dict[str, Any]:
    """``--flag key=value ...`` pairs as a dict: a key given twice or a value run.json cannot record
    is a parser error naming the flag."""
    out: dict[str, Any] = {}
    for key, value in pairs or []:
        if key in out:
            parser.error(f"{flag}: {key!r} given twice")
        out[key] = value
    try:
        json.dumps(out)
    except TypeError as exc:  # e.g. a set literal: run.json must be able to record it
        parser.error(
            f"{flag}: values must be numbers, strings, booleans, None, lists/tuples or dicts, "
            f"to be recorded in run.json ({exc})"
        )
    return out
