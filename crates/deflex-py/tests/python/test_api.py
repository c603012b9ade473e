"""The public API is documented and typed: every name of ``deflex.__all__`` (and of
``deflex.sim``), and every public method and property of its classes, has a docstring."""

from __future__ import annotations

import inspect
from typing import List

import deflex


def public_members(obj: object) -> List[str]:
    return [n for n in dir(obj) if not n.startswith("_")]


def test_every_public_name_has_a_docstring() -> None:
    missing: List[str] = []
    for name in deflex.__all__ + [f"sim.{n}" for n in deflex.sim.__all__]:
        obj: object = deflex
        for part in name.split("."):
            obj = getattr(obj, part)
        if name == "__version__" or name == "FORMATS":
            continue
        if not (getattr(obj, "__doc__", None) or "").strip():
            missing.append(name)
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            for member in public_members(obj):
                attr = getattr(obj, member)
                if not (getattr(attr, "__doc__", None) or "").strip():
                    missing.append(f"{name}.{member}")
    assert not missing, missing


def test_the_package_is_typed() -> None:
    from pathlib import Path

    package = Path(deflex.__file__).parent
    assert (package / "py.typed").is_file() and (package / "_deflex.pyi").is_file()
