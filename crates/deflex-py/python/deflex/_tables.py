"""Tables handed to deflex: a CSV path, a pandas DataFrame, or a mapping of column name to a
sequence (numpy array, list). In-memory tables are written as CSV text (numbers in their
shortest round-trip form) and parsed by the same Rust reader as the CLI's files, so the same
checks and messages apply; a bad row is named by its index (``DataFrame row 3: column `dz_m`:
…``)."""

from __future__ import annotations

import io
import math
import os
from typing import Any, List, Mapping, Sequence, Tuple, Union

import numpy as np

from ._errors import InputTypeError

#: A table argument: a CSV file path, a pandas DataFrame or a mapping of columns.
Table = Union[str, "os.PathLike[str]", Mapping[str, Any], Any]

Source = Union[Tuple[str, str], Tuple[str, str, str]]

#: Longest column of an in-memory table (rows), as the file readers bound them.
MAX_TABLE_ROWS = 2_000_000


def _cell(value: Any) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "1" if value else "0"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        f = float(value)
        return "" if math.isnan(f) else repr(f)
    if value is None:
        return ""
    return str(value)


def _mapping_to_csv(columns: Mapping[str, Any], name: str) -> str:
    names = [str(k) for k in columns.keys()]
    if not names:
        raise InputTypeError(f"{name}: the table has no columns")
    values = []
    length = None
    for key in columns:
        column = columns[key]
        if isinstance(column, (str, bytes)) or not hasattr(column, "__len__"):
            raise InputTypeError(
                f"{name}: column `{key}` must be a sequence (numpy array, list), got {type(column).__name__}"
            )
        if length is None:
            length = len(column)
        elif len(column) != length:
            raise InputTypeError(
                f"{name}: column `{key}` has {len(column)} values, the first column {length}"
            )
        values.append(column)
    if length is not None and length > MAX_TABLE_ROWS:
        raise InputTypeError(f"{name}: {length} rows, more than the {MAX_TABLE_ROWS} read")
    out = io.StringIO()
    out.write(",".join(names) + "\n")
    for i in range(length or 0):
        out.write(",".join(_cell(c[i]) for c in values) + "\n")
    return out.getvalue()


def source(data: Table, name: str = "data") -> Source:
    """The Rust engine's view of a table argument: ``("file", path)`` or ``("table", csv,
    origin)``."""
    if isinstance(data, (str, os.PathLike)):
        return ("file", os.fspath(data))
    to_csv = getattr(data, "to_csv", None)
    if callable(to_csv) and hasattr(data, "columns"):
        if len(data) > MAX_TABLE_ROWS:
            raise InputTypeError(f"{name}: {len(data)} rows, more than the {MAX_TABLE_ROWS} read")
        text = to_csv(index=False, lineterminator="\n", float_format=None)
        return ("table", str(text), "DataFrame")
    if isinstance(data, Mapping):
        return ("table", _mapping_to_csv(data, name), "table")
    raise InputTypeError(
        f"{name}: expected a CSV file path, a pandas DataFrame or a mapping of columns, got {type(data).__name__}"
    )


def sources(data: Union[Table, Sequence[Table], None], name: str) -> List[Source]:
    """Several tables (a list) or one."""
    if data is None:
        return []
    if isinstance(data, (list, tuple)):
        return [source(d, name) for d in data]
    return [source(data, name)]
