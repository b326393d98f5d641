"""Checking the diagnosis against a folder of logs with known answers (``csjm validate FOLDER``).

A validation folder holds measurement-log pairs (training and test), their rig files and an
``answers.json``: case name -> ``{"effects": [vocabulary names], "accept": rule, "rig": file,
"train": file, "test": file, "injected": {...}}`` (paths relative to the folder). Each case is
diagnosed with the standard command (``csjm diagnose TRAIN --rig RIG --test TEST``, no per-set
options) and scored by its accept rule:

``exact``
    every listed effect is the verdict (``selected``) or its secondary; ``none`` when the list
    is empty.
``no_effect``
    the verdict is ``none`` or ``unexplained``.
``not_confident``
    the verdict is ``unexplained``, or carries a warning, or its selected candidate is flagged
    implausible: a fault outside the vocabulary is never named confidently as something it is not.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any, Mapping

from ...errors import InvalidInput

#: The accept rules an ``answers.json`` may name.
ACCEPT_RULES = ("exact", "no_effect", "not_confident")
#: Keys every case of ``answers.json`` must have.
CASE_KEYS = ("effects", "accept", "rig", "train", "test")


@dataclasses.dataclass(frozen=True)
class Case:
    """One log pair of a validation folder, with its answer."""

    folder: str
    name: str
    effects: tuple[str, ...]
    accept: str
    rig: Path
    train: Path
    test: Path

    @property
    def label(self) -> str:
        """``folder/name``, the case's name in reports."""
        return f"{self.folder}/{self.name}"


def load_cases(folder: str | Path, vocabulary: tuple[str, ...] | None = None) -> list[Case]:
    """The cases of a validation folder, checked before anything runs.

    Parameters
    ----------
    folder : str or Path
        A folder holding ``answers.json`` and the files it names.
    vocabulary : tuple of str, optional
        Names an answer's ``effects`` may use (default: not checked).

    Returns
    -------
    list of Case
        In the order of ``answers.json``.

    Raises
    ------
    InvalidInput
        No folder, no ``answers.json``, malformed JSON, a case without one of :data:`CASE_KEYS`,
        an unknown accept rule or effect name, or a file the case names that does not exist.
    """
    root = Path(folder)
    if not root.is_dir():
        raise InvalidInput(f"{root}: not a folder", "FOLDER")
    path = root / "answers.json"
    if not path.is_file():
        raise InvalidInput(f"{root}: no answers.json (a validation folder needs the answers to score against)",
                           "answers.json")
    try:
        answers = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InvalidInput(f"{path}: not readable JSON ({exc})", "answers.json") from exc
    if not isinstance(answers, dict) or not answers:
        raise InvalidInput(f"{path}: expected an object of cases (name -> answer), got {type(answers).__name__}"
                           + (" (empty)" if isinstance(answers, dict) else ""), "answers.json")
    cases = []
    for name, a in answers.items():
        if not isinstance(a, dict):
            raise InvalidInput(f"{path}: case {name!r} is not an object", name)
        missing = [k for k in CASE_KEYS if k not in a]
        if missing:
            raise InvalidInput(f"{path}: case {name!r} has no {', '.join(missing)}", name)
        if a["accept"] not in ACCEPT_RULES:
            raise InvalidInput(f"{path}: case {name!r}: unknown accept rule {a['accept']!r}; expected one of "
                               f"{', '.join(ACCEPT_RULES)}", f"{name}.accept")
        effects = a["effects"]
        if not isinstance(effects, list) or not all(isinstance(e, str) for e in effects):
            raise InvalidInput(f"{path}: case {name!r}: effects must be a list of names", f"{name}.effects")
        unknown = [e for e in effects if vocabulary is not None and e not in vocabulary]
        if unknown:
            raise InvalidInput(f"{path}: case {name!r}: unknown effect {unknown[0]!r}", f"{name}.effects")
        files = {}
        for key in ("rig", "train", "test"):
            f = root / str(a[key])
            if not f.is_file():
                raise InvalidInput(f"{path}: case {name!r}: {key} file {f} does not exist", f"{name}.{key}")
            files[key] = f
        cases.append(Case(root.name, str(name), tuple(effects), a["accept"], files["rig"], files["train"],
                          files["test"]))
    return cases


def confident(result: Mapping[str, Any]) -> bool:
    """Whether a diagnosis names an effect confidently: named, no warning, selected candidate plausible.

    Parameters
    ----------
    result : mapping
        ``csjm diagnose`` JSON.

    Returns
    -------
    bool
    """
    selected = result.get("selected")
    if selected in (None, "none", "unexplained"):
        return False
    if (result.get("verdict") or {}).get("warnings"):
        return False
    cand = next((c for c in result.get("candidates", []) if c.get("effect") == selected), None)
    return not (cand is not None and cand.get("plausible") is False)


def accepted(rule: str, effects: tuple[str, ...] | list[str], result: Mapping[str, Any]) -> bool:
    """Whether a diagnosis passes a case's accept rule (module doc).

    Parameters
    ----------
    rule : str
        One of :data:`ACCEPT_RULES`.
    effects : sequence of str
        The answer's effects.
    result : mapping
        ``csjm diagnose`` JSON.

    Returns
    -------
    bool

    Raises
    ------
    InvalidInput
        Unknown rule.
    """
    selected = result.get("selected")
    if rule == "exact":
        if not effects:
            return selected == "none"
        named = {selected, (result.get("secondary") or {}).get("effect")}
        return all(e in named for e in effects)
    if rule == "no_effect":
        return selected in ("none", "unexplained")
    if rule == "not_confident":
        return not confident(result)
    raise InvalidInput(f"unknown accept rule {rule!r}; expected one of {', '.join(ACCEPT_RULES)}", "accept")


def verdict_line(result: Mapping[str, Any]) -> str:
    """The verdict in a few words: ``selected[+secondary]`` and ``(warned)`` when it carries warnings."""
    sec = (result.get("secondary") or {}).get("effect", "none")
    name = str(result.get("selected")) + ("" if sec in (None, "none") else f"+{sec}")
    return name + (" (warned)" if (result.get("verdict") or {}).get("warnings") else "")


def summarise(scored: list[dict]) -> dict[str, dict]:
    """Per folder: ``{"right": k, "cases": n, "share": k / n}`` from entries with ``folder`` and ``right``."""
    out: dict[str, dict] = {}
    for s in scored:
        f = out.setdefault(s["folder"], {"right": 0, "cases": 0})
        f["cases"] += 1
        f["right"] += int(bool(s["right"]))
    for f in out.values():
        f["share"] = f["right"] / f["cases"]
    return out
