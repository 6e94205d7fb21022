"""The ``--csv`` layout of each kind of record: its columns, and how one record fills them.

A layout reads the record ``--json`` prints (built by the library: ``props_record``,
``bounds_record``, ``check_record``, ``RepairReport.to_dict``), or the error record of an
input that could not be done (``source``, ``error``); a column the record does not fill is
empty. ``p3d_cli.cli.output.formatted`` is the one writer that uses them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from p3d_cli.cli.rounding import snapped

#: Significant digits of ``--csv`` numbers by default: what a spreadsheet keeps (IEEE doubles
#: hold 15-17; 15 always round-trips a decimal, so 94.19999999999999 reads back as 94.2).
CSV_PRECISION = 15


@dataclass(frozen=True)
class Columns:
    """One kind of record's ``--csv`` layout.

    Attributes
    ----------
    names : tuple of str
        The header, in order.
    cells : callable
        ``cells(record) -> dict``: the record's cells by column name (others are empty).
    about : tuple of str
        Columns added before the last two when ``--about`` is given (props).
    rows : callable
        ``rows(record) -> list of dict``: the records one record writes as rows (props: each
        part's, then the whole's).
    precision : int or None
        Significant digits of floats by default (None: full precision, ``repr``).
    """

    names: tuple[str, ...]
    cells: Callable[[dict], dict]
    about: tuple[str, ...] = ()
    rows: Callable[[dict], list] = lambda record: [record]
    precision: int | None = CSV_PRECISION

    def header(self, about: bool = False) -> tuple[str, ...]:
        """The column names (with the ``--about`` columns when asked for)."""
        if not about or not self.about:
            return self.names
        return self.names[:-2] + self.about + self.names[-2:]

    def row(self, record: dict, about: bool = False) -> list:
        """One record's cells in column order."""
        names = self.header(about)
        row = dict.fromkeys(names)
        row.update({k: v for k, v in self.cells(record).items() if k in row})
        return [row[k] for k in names]


def _xyz(prefix: str, vector) -> dict:
    return dict(zip((f"{prefix}x", f"{prefix}y", f"{prefix}z"), (float(x) for x in vector)))


def _tensor(prefix: str, matrix) -> dict:
    i = np.asarray(matrix)
    return {f"{prefix}ixx": i[0, 0], f"{prefix}iyy": i[1, 1], f"{prefix}izz": i[2, 2],
            f"{prefix}ixy": i[0, 1], f"{prefix}ixz": i[0, 2], f"{prefix}iyz": i[1, 2]}


def _codes(record: dict) -> str | None:
    """The warnings as their codes, space-separated (empty without any)."""
    return " ".join(record.get("warning_codes") or []) or None


def _props_cells(record: dict) -> dict:
    row = dict(record)
    if record.get("center_of_mass") is not None:
        row.update(_xyz("com_", record["center_of_mass"]))
    if record.get("inertia") is not None:
        row.update(_tensor("", record["inertia"]))
    if record.get("principal_moments") is not None:
        row.update(zip(("i1", "i2", "i3"), (float(x) for x in record["principal_moments"])))
    if record.get("bounds") is not None:
        row.update(_xyz("min_", record["bounds"]["min"]), **_xyz("max_", record["bounds"]["max"]))
    if record.get("about") is not None:
        row.update(_xyz("about_", record["about"]))
        if record.get("inertia_about") is not None:
            row.update(_tensor("about_", record["inertia_about"]))
    row["warnings"] = _codes(record)
    return row


def _props_rows(record: dict) -> list:
    """An assembly's parts (named ``SOURCE#PART``), then the whole; values within their rounding
    bound of zero as 0 (``p3d_cli.cli.rounding``)."""
    parts = [{**part, "source": f"{record['source']}#{part['name']}"} for part in record.get("parts", ())]
    return [snapped(row) for row in parts + [record]]


def _bounds_cells(record: dict) -> dict:
    row = dict(record)
    for end in ("min", "max"):
        if record.get(end) is not None:
            row.update(_xyz(f"{end}_", record[end]))
    row["warnings"] = _codes(record)
    return row


def _check_cells(record: dict) -> dict:
    row = dict(record)
    if isinstance(row.get("self_intersections"), dict):
        row["self_intersections"] = row["self_intersections"]["count"]
    if isinstance(row.get("failed"), list):
        row["failed"] = " ".join(row["failed"])
    return row


def _repair_cells(record: dict) -> dict:
    if "steps" not in record:       # an error record
        return dict(record)
    steps = {s["step"]: s["counts"] for s in record["steps"]}
    mass = record["mass"]
    return {"source": record["source"], "output": record["output"] or "", "ok": record["ok"],
            "fixed": record["fixed"], "changed": record["changed"], "written": record["written"],
            "failed_before": " ".join(record["before"]["failed"]), "failed_after": " ".join(record["after"]["failed"]),
            "faces_removed": sum(steps.get(n, {}).get("faces_removed", 0) for n in ("degenerate", "duplicate")),
            "faces_flipped": sum(steps.get(n, {}).get("faces_flipped", 0) for n in ("orient", "outward")),
            "holes_filled": steps.get("holes", {}).get("holes_filled", 0),
            "holes_left": steps.get("holes", {}).get("holes_left", 0),
            "faces_added": steps.get("holes", {}).get("faces_added", 0),
            "volume_before": mass["before"]["volume"], "volume_after": mass["after"]["volume"],
            "relative_volume_change": mass["relative_volume_change"]}


#: Each kind of record that ``--csv`` writes, with its layout (``p3d props --csv`` etc.).
#: props: inertia about the centre of mass, positive tensor convention; ``i1..i3`` the
#: principal moments (ascending); ``warnings`` the warnings' codes, space-separated.
COLUMNS: dict[str, Columns] = {
    "props": Columns(
        ("source", "format", "method", "faces", "closed", "volume", "mass", "density",
         "com_x", "com_y", "com_z", "ixx", "iyy", "izz", "ixy", "ixz", "iyz",
         "i1", "i2", "i3", "min_x", "min_y", "min_z", "max_x", "max_y", "max_z",
         "warnings", "error"),
        _props_cells,
        about=("about_x", "about_y", "about_z", "about_ixx", "about_iyy", "about_izz", "about_ixy",
               "about_ixz", "about_iyz"),
        rows=_props_rows),
    "bounds": Columns(
        ("source", "format", "method", "faces", "min_x", "min_y", "min_z", "max_x", "max_y", "max_z",
         "warnings", "error"),
        _bounds_cells),
    "check": Columns(
        ("source", "format", "ok", "failed", "faces", "vertices", "edges", "closed", "oriented",
         "outward", "manifold", "boundary_edges", "nonmanifold_edges", "misoriented_edges",
         "nonmanifold_vertices", "degenerate_faces", "zero_area_faces",
         "faces_with_repeated_vertex", "duplicate_faces", "shells", "volume", "error", "signed_volume",
         "self_intersections"),
        _check_cells, precision=None),
    "repair": Columns(
        ("source", "output", "ok", "fixed", "changed", "written", "failed_before", "failed_after",
         "faces_removed", "faces_flipped", "holes_filled", "holes_left", "faces_added",
         "volume_before", "volume_after", "relative_volume_change", "error"),
        _repair_cells, precision=None),
}
