"""Logs and tables as columns: a twin run's log, a ``deflex run`` log, a ``deflex sim isf``
log, a compensated path or a prediction file, numpy arrays by column name (and a pandas
DataFrame when pandas is installed; deflex never needs it)."""

from __future__ import annotations

import os
from typing import Any, Dict, Iterator, List, Union

import numpy as np
import numpy.typing as npt

from . import _deflex

__all__ = ["Log", "read_log"]

Column = npt.NDArray[Any]


class Log:
    """Named columns of equal length: numeric columns are float64 numpy arrays (empty cells
    NaN), text columns numpy arrays of Python ``str`` (dtype object). Column names carry their unit (``time_s``,
    ``fz_N``, ``q3_rad``). ``comments`` holds the file's header comments; ``simulated`` is
    true when they say SIMULATED."""

    def __init__(self, columns: Dict[str, Any], comments: List[str], simulated: bool) -> None:
        self.columns: Dict[str, Column] = {
            k: v if isinstance(v, np.ndarray) else np.array(v, dtype=object) for k, v in columns.items()
        }
        self.comments: List[str] = list(comments)
        self.simulated: bool = bool(simulated)

    @property
    def names(self) -> List[str]:
        """Column names, in file order."""
        return list(self.columns)

    def __len__(self) -> int:
        """Number of rows."""
        for column in self.columns.values():
            return len(column)
        return 0

    def __getitem__(self, name: str) -> Column:
        """A column by name; a ``KeyError`` lists the names there are."""
        try:
            return self.columns[name]
        except KeyError:
            raise KeyError(f"no column {name!r}; columns: {', '.join(self.columns)}") from None

    def __contains__(self, name: object) -> bool:
        return name in self.columns

    def __iter__(self) -> Iterator[str]:
        return iter(self.columns)

    def array(self, *names: str) -> npt.NDArray[np.float64]:
        """The numeric columns ``names`` side by side, shape ``(rows, len(names))``."""
        return np.column_stack([np.asarray(self[n], dtype=np.float64) for n in names])

    def to_pandas(self) -> Any:
        """The log as a ``pandas.DataFrame`` (needs pandas; deflex itself does not)."""
        try:
            import pandas as pd  # type: ignore[import-untyped,unused-ignore]
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError(
                "Log.to_pandas() needs pandas (pip install pandas); the columns are in Log.columns as numpy arrays"
            ) from e
        frame = pd.DataFrame({k: v for k, v in self.columns.items()})
        frame.attrs["comments"] = list(self.comments)
        frame.attrs["simulated"] = self.simulated
        return frame

    def __repr__(self) -> str:
        tag = "SIMULATED, " if self.simulated else ""
        return f"Log({tag}{len(self)} rows, columns: {', '.join(self.columns)})"


def read_log(path: Union[str, "os.PathLike[str]"]) -> Log:
    """Read a deflex CSV file (a ``deflex run`` log, a ``deflex sim isf`` ``log.csv``, a
    ``compensated_path.csv``, a measurement or prediction file) as a :class:`Log`. Bounded
    (1 GiB, 20 million rows, 4096 columns); errors name the file and line."""
    result: Log = _deflex._read_table(os.fspath(path))
    return result
