"""The C kernel's reader of recorded tables (c_kernel/src/recorded_motion_csv.c) for Python: the one
reader of every recorded CSV the product takes (a ship-motion recording, a target's or a carrier's
track), so that all are refused alike: a header with a 'time' column and no name twice, a finite
number in every cell, at least 4 rows, time strictly increasing, UTF-8 with or without a byte-order
mark; a refusal names the line and the column."""
from __future__ import annotations

import ctypes

import numpy as np

from . import kernel

MESSAGE_BYTES = 1024


class _Table(ctypes.Structure):
    """GimbalCsvTable (recorded_motion_csv.h)."""
    _fields_ = [("columns", ctypes.c_int), ("names", ctypes.POINTER(ctypes.c_char_p)), ("rows", ctypes.c_long),
                ("values", ctypes.POINTER(ctypes.c_double)), ("time_column", ctypes.c_int)]


class TableRefused(ValueError):
    """The text is not a recorded table; the message says why (the line, the column), without the file."""


def _declared():
    loaded = kernel()
    loaded.gimbal_csv_table_read.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.POINTER(_Table),
                                             ctypes.c_char_p, ctypes.c_size_t]
    loaded.gimbal_csv_table_read.restype = ctypes.c_int
    loaded.gimbal_csv_table_free.argtypes = [ctypes.POINTER(_Table)]
    loaded.gimbal_csv_table_free.restype = None
    return loaded


def read_table(text: bytes) -> tuple[list[str], np.ndarray]:
    """(column names, values of shape (rows, columns)) of a recorded table's bytes; TableRefused with
    the reader's reason, MemoryError when the kernel could not allocate."""
    loaded = _declared()
    table = _Table()
    message = ctypes.create_string_buffer(MESSAGE_BYTES)
    status = loaded.gimbal_csv_table_read(text, len(text), ctypes.byref(table), message, len(message))
    if status == 1:
        raise TableRefused(message.value.decode("utf-8", "replace"))
    if status != 0:
        raise MemoryError("the recorded table")
    try:
        names = [table.names[k].decode("utf-8", "replace") for k in range(table.columns)]
        values = np.ctypeslib.as_array(table.values, shape=(table.rows, table.columns)).copy()
    finally:
        loaded.gimbal_csv_table_free(ctypes.byref(table))
    return names, values
