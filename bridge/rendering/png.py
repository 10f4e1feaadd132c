"""PNG files of rendered pictures: encoded here (zlib, no row filter), written atomically, on a
background thread when many are written one after the other.

A report's pictures are rendered one by one (VTK, in the calling thread) and each is then encoded
and written. zlib releases the GIL, so :class:`PngWriter` encodes picture k on a thread of its own
while picture k + 1 renders.

Why not Pillow's encoder (used before 2026-12-06, and still what reads PNGs): it picks a row filter
adaptively, which suits photographs; rendered pictures (flat shading, a uniform background, stripes)
compress better without one, and the filtering itself costs time. On the 76 pictures of the OCCT
bearing's and linkrods' reports (900 x 640 model pictures, 440 x 330 face pictures): Pillow at zlib
level 6 3.93 s and 10.9 MB; unfiltered rows at level 4 (:data:`REPORT_PNG_LEVEL`) 0.90 s and
9.2 MB, level 5 1.45 s and 8.9 MB, level 6 2.97 s and 8.4 MB. The file is the standard's minimum
(IHDR, one IDAT, IEND; 8 bits per channel, filter type 0 on every row): the same pixels, which
Pillow, browsers and VTK decode.
"""

from __future__ import annotations

import os
import struct
import threading
import zlib
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from types import TracebackType

import numpy as np

__all__ = ["png_bytes", "write_png_file", "PngWriter", "REPORT_PNG_LEVEL"]

#: zlib level of the pictures :class:`PngWriter` writes (see the module's notes).
REPORT_PNG_LEVEL = 4

_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_COLOUR_TYPE = {1: 0, 3: 2, 4: 6}  # channels -> PNG colour type: grey, RGB, RGB with alpha


def _chunk(kind: bytes, data: bytes) -> bytes:
    """A PNG chunk: length, type, data and the CRC-32 of type and data."""
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png_bytes(rgb: np.ndarray, level: int = REPORT_PNG_LEVEL) -> bytes:
    """The PNG encoding of an ``(height, width, 3)`` (or ``(h, w, 4)``, or grey ``(h, w)``) uint8
    image at zlib ``level``, its rows unfiltered (see the module's notes).

    Raises
    ------
    ValueError
        Not such an image (another number of channels, or an empty one).
    """
    a = np.ascontiguousarray(rgb, np.uint8)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3 or a.shape[2] not in _COLOUR_TYPE or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"png: expected an image of shape (height, width) or (height, width, 3 or 4), "
                         f"got {np.shape(rgb)}")
    h, w, c = a.shape
    rows = np.zeros((h, w * c + 1), np.uint8)  # each row: its filter type (0, none), then its bytes
    rows[:, 1:] = a.reshape(h, w * c)
    header = struct.pack(">IIBBBBB", w, h, 8, _COLOUR_TYPE[c], 0, 0, 0)  # 8 bits, deflate, filter set 0, no interlace
    return (_SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(rows.tobytes(), int(level)))
            + _chunk(b"IEND", b""))


def write_png_file(path: str | os.PathLike[str], rgb: np.ndarray, level: int = REPORT_PNG_LEVEL) -> Path:
    """Encode ``rgb`` and write it to ``path`` atomically (a failed write leaves no partial file and
    keeps an existing one); returns the path."""
    from ..exchange.files import atomic_write

    p = Path(path)
    atomic_write(p, png_bytes(rgb, level))
    return p


class PngWriter:
    """Writes PNGs on background threads; at most ``pending`` images wait at once (``write`` blocks
    beyond that, so a model of thousands of faces does not queue thousands of images).

    ``write`` returns a :class:`~concurrent.futures.Future` of the path (its exception is the
    encoder's or the file system's); :meth:`close` (or leaving the ``with`` block) waits for every
    file. With ``threads=0`` each ``write`` encodes and writes at once, in the calling thread.
    """

    def __init__(self, level: int = REPORT_PNG_LEVEL, *, threads: int | None = None, pending: int = 8) -> None:
        if threads is None:  # one core renders; the others encode (at most two: zlib is the only work)
            threads = max(1, min(2, (os.cpu_count() or 1) - 1))
        self.level = int(level)
        self._pool = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="occsurf-png") if threads > 0 else None
        self._slots = threading.BoundedSemaphore(max(1, int(pending)))

    def write(self, path: str | os.PathLike[str], rgb: np.ndarray) -> Future[Path]:
        """Encode and write ``rgb`` to ``path`` (atomically), later or now; the future of the path."""
        if self._pool is None:
            done: Future[Path] = Future()
            try:
                done.set_result(write_png_file(path, rgb, self.level))
            except Exception as err:  # noqa: BLE001 - handed to the caller through the future
                done.set_exception(err)
            return done
        self._slots.acquire()
        try:
            fut = self._pool.submit(write_png_file, path, rgb, self.level)
        except BaseException:
            self._slots.release()
            raise
        fut.add_done_callback(lambda _f: self._slots.release())
        return fut

    def close(self) -> None:
        """Wait for every file written so far."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)

    def __enter__(self) -> PngWriter:
        return self

    def __exit__(self, kind: type[BaseException] | None, err: BaseException | None, tb: TracebackType | None) -> None:
        self.close()
