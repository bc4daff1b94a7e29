"""String columns of Parquet tables as numpy, without a Python string per row.

A long dataset has hundreds of thousands of rows whose class or camera is one of a handful of names; these
helpers go through Arrow's dictionary encoding, so a column costs 8 bytes a row (a code, or a pointer to one
shared string) instead of a new string object per row.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from ..errors import DatasetError


def _encoded(column: pa.ChunkedArray | pa.Array) -> pa.DictionaryArray:
    encoded = pc.dictionary_encode(column)
    return encoded.combine_chunks() if isinstance(encoded, pa.ChunkedArray) else encoded


def shared_strings(column: pa.ChunkedArray | pa.Array) -> np.ndarray:
    """``(R,)`` object array of a string column without nulls, one Python string per distinct value.

    >>> shared_strings(pa.array(["car", "bus", "car"])).tolist()
    ['car', 'bus', 'car']
    """
    encoded = _encoded(column)
    values = np.array(encoded.dictionary.to_pylist(), dtype=object)
    if len(values) == 0:
        return np.zeros(len(encoded), dtype=object)
    return values[encoded.indices.to_numpy(zero_copy_only=False)]


def string_codes(column: pa.ChunkedArray | pa.Array, codes: dict[str, int], what: str) -> np.ndarray:
    """``(R,)`` int64 code of each string of ``column`` (e.g. a camera or class name → its index); a
    :class:`DatasetError` naming ``what`` for a value ``codes`` lacks.

    >>> string_codes(pa.array(["b", "a", "b"]), {"a": 0, "b": 1}, "letters").tolist()
    [1, 0, 1]
    """
    encoded = _encoded(column)
    names = encoded.dictionary.to_pylist()
    unknown = sorted(set(names) - set(codes))
    if unknown:
        raise DatasetError(f"{what}: unknown value(s) {unknown} (expected one of {sorted(codes)})")
    if not names:
        return np.zeros(len(encoded), dtype=np.int64)
    lookup = np.array([codes[name] for name in names], dtype=np.int64)
    return lookup[encoded.indices.to_numpy(zero_copy_only=False)]
