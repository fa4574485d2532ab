"""`gearlab validate` reads a MAT file's header, not its data (gearlab.data.readers.headers): a user's
1 GB .mat was read whole (MAT v5: every byte, and every compressed variable inflated) to list its
channels. Each format's header is read with the bytes the process reads counted (/proc/self/io) and the
memory it holds (tracemalloc): a few kB of a 16 MB record, v5 (plain, compressed, a scalar struct's
fields), v7.3 (HDF5) and v4 alike, under 1 MB held, with the channels and shapes as before; a compressed
struct's fields lie in one deflate stream, so a field after the data is reached by inflating through it,
streamed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io

from gearlab.data.recordings import check_recording, read_header

FS = 25600.0
ROWS = 1_000_000  # 2 columns of doubles: 16 MB
IO = Path("/proc/self/io")


def _read_bytes() -> int:
    return int(next(line for line in IO.read_text().splitlines() if line.startswith("rchar:")).split()[1])


def _write(path: Path, kind: str) -> None:
    data = np.random.default_rng(0).standard_normal((ROWS, 2))  # no compression makes it small
    if kind == "v5":
        scipy.io.savemat(path, {"data": data, "fs": FS})
    elif kind == "v5-compressed":
        scipy.io.savemat(path, {"data": data, "fs": FS}, do_compression=True)
    elif kind == "v5-struct":
        scipy.io.savemat(path, {"rec": {"data": data, "fs": FS}, "note": "take 1"})
    elif kind == "v5-struct-compressed":
        scipy.io.savemat(path, {"rec": {"data": data, "fs": FS}, "note": "take 1"}, do_compression=True)
    elif kind == "v4":
        scipy.io.savemat(path, {"data": data, "fs": FS}, format="4")
    else:
        from test_importers import write_mat73

        write_mat73(path, {"data": data, "fs": FS})  # HDF5 holds MATLAB's arrays transposed: (2, ROWS)


EXPECTED = {
    "v5": (["data", "fs"], {"data": (ROWS, 2), "fs": (1, 1)}, "data[1]"),
    "v5-compressed": (["data", "fs"], {"data": (ROWS, 2), "fs": (1, 1)}, "data[1]"),
    "v5-struct": (["rec", "note", "rec/data", "rec/fs"], {"rec/data": (ROWS, 2), "rec/fs": (1, 1)}, "rec.data[1]"),
    "v5-struct-compressed": (
        ["rec", "note", "rec/data", "rec/fs"],
        {"rec/data": (ROWS, 2), "rec/fs": (1, 1)},
        "rec.data[1]",
    ),
    "v4": (["data", "fs"], {"data": (ROWS, 2), "fs": (1, 1)}, "data[1]"),
    "v7.3": (["data", "fs"], {"data": (2, ROWS), "fs": (1, 1)}, "data[1]"),
}


@pytest.mark.skipif(not IO.exists(), reason="the bytes a process reads are counted in /proc/self/io (Linux)")
@pytest.mark.parametrize("kind", list(EXPECTED))
def test_validate_reads_a_mat_file_s_header_not_its_data(tmp_path, kind):
    import tracemalloc

    path = tmp_path / "take.mat"
    _write(path, kind)
    size = path.stat().st_size
    assert size > 15e6, size  # the data part is most of the file, compressed or not
    read_header(path)  # once: the readers' modules imported
    before = _read_bytes()
    tracemalloc.start()
    header = read_header(path)
    held = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    read = _read_bytes() - before
    if kind == "v5-struct-compressed":  # its 'fs' field lies after 'data' in one deflate stream: inflated
        assert read < 1.01 * size, f"{kind}: {read:,} bytes read of {size:,}"  # through, once, never held
    else:
        assert read < 200_000, f"{kind}: {read:,} bytes read of {size:,}"
    assert held < 1_000_000, f"{kind}: {held:,} bytes held"
    channels, shapes, column = EXPECTED[kind]
    assert header.channels == channels and header.rate
    assert {k: header.shapes[k] for k in shapes} == shapes, header.shapes
    check_recording(path, "s.toml: [target]", {"vibration": column}, unit="m/s^2")  # validate's check
