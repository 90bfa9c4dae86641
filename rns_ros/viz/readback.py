"""Read a saved ``.rrd`` back: which entities it holds, how many rows, and the plotted values.

rerun 0.41 has no ``rerun.dataframe`` module any more (its DataFusion reader needs the optional
``datafusion`` package, not installed here); the chunk API does the job: ``rerun.chunk.RrdReader``
streams the chunks of the file's first recording, each with its entity path and an Arrow record
batch (one column per timeline and per component).
"""

from __future__ import annotations

import contextlib
from collections import Counter
from pathlib import Path

import numpy as np
import pyarrow as pa
from rerun.chunk import RrdReader

from rns_ros.core.errors import InputError
from rns_ros.viz import paths

_SCALARS = "Scalars:scalars"
_ROW_ID = "rerun.controls.RowId"


def _entity(path: str) -> str:
    """Entity path as in :mod:`rns_ros.viz.paths`: no leading slash (the root stays "/")."""
    return path.lstrip("/") or "/"


def _reader(path: str | Path) -> RrdReader:
    path = Path(path)
    if not path.is_file():
        raise InputError(f"no recording at {path}")
    return RrdReader(path)


def rrd_problem(path: str | Path) -> str | None:
    """Why the file at ``path`` is not a complete ``.rrd`` (missing, cut short, not rerun's
    encoding: every chunk is decoded, as ``rerun rrd verify`` does), or None when it is one."""
    import warnings

    path = Path(path)
    if not path.is_file():
        return "the file does not exist"
    try:
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            reader = RrdReader(path)
            for _chunk in reader.stream():
                pass
    except (RuntimeError, ValueError, OSError) as exc:
        return storage_limit(path) or " ".join(str(exc).split()).replace(f" at {path}", "")
    # a file sink that was closed writes a footer: without it the file was cut short, maybe at
    # a frame boundary, where every chunk still decodes
    if any("no footer" in str(warning.message) for warning in said):
        return storage_limit(path) or "the file ends before rerun's footer: it was cut short"
    return None


#: Free space [bytes] below which a file cut short is put down to a full disk.
FULL_DISK_MARGIN = 1 << 20


def storage_limit(path: str | Path) -> str | None:
    """What stopped a file at ``path`` from growing, where this process can tell: the
    file-size limit of the process (``ulimit -f``) reached, or less than
    :data:`FULL_DISK_MARGIN` free on its file system; else None."""
    import os
    import resource

    path = Path(path)
    with contextlib.suppress(OSError):
        limit, _ = resource.getrlimit(resource.RLIMIT_FSIZE)
        if limit != resource.RLIM_INFINITY and path.is_file() and path.stat().st_size >= limit:
            return f"the file-size limit (ulimit -f) of {limit} bytes was reached"
        disk = os.statvfs(path.parent)
        if disk.f_bavail * disk.f_frsize < FULL_DISK_MARGIN:
            return "no space left on device"
    return None


def recording_summary(path: str | Path, *, include_static: bool = False) -> dict[str, int]:
    """{entity path (no leading slash): number of samples} of the file's first recording.

    A sample is one row on a timeline (one logged message for a time series, one pose for a
    joint). Entities that only hold static data (URDF geometry, ``tf_static``, series styles)
    are listed with 0, unless ``include_static`` counts their rows too.

    Raises:
        InputError: the file does not exist.
    """
    rows: Counter[str] = Counter()
    for chunk in _reader(path).stream():
        entity = _entity(chunk.entity_path)
        rows[entity] += chunk.num_rows if include_static or not chunk.is_static else 0
    return dict(rows)


def recording_ids(path: str | Path) -> list[tuple[str, str]]:
    """(application id, recording id) of every recording store in the file."""
    return [(s.application_id, s.recording_id) for s in _reader(path).recordings()]


def read_scalars(
    path: str | Path, entity: str, timeline: str = paths.TIMELINE
) -> tuple[np.ndarray, np.ndarray]:
    """A time series back from a file: (times [s], values), sorted by time, shapes (k,).

    Times are seconds on ``timeline`` (since zero for simulated time, since the Unix epoch for
    timestamps). Rows logged without that timeline are skipped.
    """
    times, values = [], []
    for chunk in _reader(path).stream():
        if _entity(chunk.entity_path) != _entity(entity) or chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        names = batch.schema.names
        if _SCALARS not in names or timeline not in names:
            continue
        stamp = batch.column(timeline)
        times.append(stamp.cast(pa.int64()).to_numpy(zero_copy_only=False) * 1e-9)
        values.append(np.array([row[0] for row in batch.column(_SCALARS).to_pylist()]))
    if not times:
        return np.zeros(0), np.zeros(0)
    t, v = np.concatenate(times), np.concatenate(values)
    order = np.argsort(t, kind="stable")
    return t[order], v[order]


def read_components(path: str | Path, entity: str) -> list[dict[str, list]]:
    """Every row of ``entity`` as {component: value} (Arrow -> Python), in file order.

    For checking what the viewer will get, e.g. the Transform3D rows of a joint.
    """
    rows = []
    for chunk in _reader(path).stream():
        if _entity(chunk.entity_path) != _entity(entity):
            continue
        batch = chunk.to_record_batch()
        columns = [name for name in batch.schema.names if ":" in name]
        data = {name: batch.column(name).to_pylist() for name in columns}
        rows.extend(
            {name: data[name][i] for name in columns if data[name][i] is not None}
            for i in range(batch.num_rows)
        )
    return rows


def read_static(path: str | Path, entity: str) -> dict[str, list]:
    """The static data of ``entity`` the viewer shows: {component: value} of the newest static
    row (by rerun's row id: a file holds chunks in flush order, not log order, and a later
    static write replaces an earlier one). Empty when the entity has no static row."""
    newest, row = b"", {}
    for chunk in _reader(path).stream():
        if _entity(chunk.entity_path) != _entity(entity) or not chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        columns = [name for name in batch.schema.names if ":" in name]
        ids = batch.column(_ROW_ID).to_pylist()
        for i, row_id in enumerate(ids):
            if row_id >= newest:
                newest = row_id
                row = {n: batch.column(n)[i].as_py() for n in columns}
                row = {n: v for n, v in row.items() if v is not None}
    return row
