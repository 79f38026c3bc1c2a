"""CCSDS Orbit Ephemeris Messages (OEM version 2.0, CCSDS 502.0-B-2 sec. 5, as kept by 502.0-B-3), KVN and XML.

``write_oem`` writes one segment of states (positions km, velocities km/s, the units the standard fixes) with an
optional covariance block per epoch, as text (KVN, sec. 5.2 and Fig. 5-1 of the standard) or as NDM/XML (CCSDS
505.0-B-2, the ``oem`` element of the NDM/XML 2.0 schema: ``header``, ``body``/``segment``/``metadata`` and
``data``/``stateVector``/``covarianceMatrix``, keywords as element names in the schema's order).  What the
states are, their frame and time system, is the caller's to say (``export.trajectory``).

Written here rather than with a library: the format is a page of text, and the candidates (``ccsds-ndm``,
GPL-3, an object tree generated from the schemas; ``oem``, which brings astropy) would add more than they
write.  ``tests/test_export.py`` reads the files back with a reader of its own and, where it is installed, with
``ccsds-ndm`` (the schema's own model).  The covariance's lower triangle keeps 8 significant digits (``7e``).
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path
from typing import NamedTuple
from xml.etree import ElementTree

import numpy as np

VERSION = "2.0"
# XML schema of the NDM/XML 2.0 master (CCSDS 505.0-B-2, SANA registry)
SCHEMA = "https://sanaregistry.org/r/ndmxml_unqualified/ndmxml-2.0.0-master-2.0.xsd"
POSITION_DECIMALS = 9  # km: 1 um (float64 resolves 7e-12 km at the GEO radius)
VELOCITY_DECIMALS = 12  # km/s: 1e-9 m/s
STATE_KEYS = ("X", "Y", "Z", "X_DOT", "Y_DOT", "Z_DOT")


class Metadata(NamedTuple):
    """A segment's metadata (502.0-B-2 Table 5-3); times are the caller's strings in ``time_system``."""

    object_name: str
    object_id: str
    ref_frame: str  # EME2000, GCRF, MOD, TOD, ... (SANA reference frames)
    time_system: str  # UTC, TT, TAI, ...
    start_time: str
    stop_time: str
    center_name: str = "EARTH"
    ref_frame_epoch: str | None = None  # for a frame whose epoch is not in its name (e.g. MOD of an epoch)
    comments: tuple[str, ...] = ()
    interpolation: str | None = None  # the method a reader should interpolate the states with (e.g. LAGRANGE)
    interpolation_degree: int | None = None  # its polynomial degree


class Covariance(NamedTuple):
    """A 6 x 6 position-velocity covariance (km**2, km**2/s, km**2/s**2) at ``epoch``, in ``ref_frame`` (None:
    the segment's)."""

    epoch: str
    matrix: np.ndarray  # [6, 6], symmetric
    ref_frame: str | None = None


def write_oem(path: str | Path, metadata: Metadata, epochs: list[str], states_km: np.ndarray, *,
              originator: str = "geojax", covariances: tuple[Covariance, ...] = (), comments: tuple[str, ...] = (),
              data_comments: tuple[str, ...] = (), xml: bool | None = None,
              created: dt.datetime | None = None) -> Path:
    """Write one segment of ``states_km`` [n, 6] (x, y, z km, vx, vy, vz km/s) at ``epochs`` [n] to ``path``.

    ``xml``: NDM/XML, else KVN; None: XML where ``path`` ends in ``.xml``.  ``comments`` go in the header,
    ``data_comments`` before the states.  Returns the path.
    """
    path = Path(path)
    states_km = np.asarray(states_km, dtype=float)
    if states_km.ndim != 2 or states_km.shape[1] != 6 or len(epochs) != len(states_km):
        raise ValueError(f"states_km: need [n, 6] for {len(epochs)} epochs, got {states_km.shape}")
    created = (created or dt.datetime.now(dt.timezone.utc)).strftime("%Y-%m-%dT%H:%M:%S")
    xml = path.suffix.lower() == ".xml" if xml is None else xml
    write = _xml if xml else _kvn
    text = write(metadata, epochs, states_km, originator, covariances, comments, data_comments, created)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".partial")
    partial.write_text(text)
    partial.replace(path)
    return path


def state_fields(state_km) -> list[str]:
    """The six numbers of a state as written: positions to ``POSITION_DECIMALS``, velocities to
    ``VELOCITY_DECIMALS`` decimals."""
    return ([f"{x:.{POSITION_DECIMALS}f}" for x in state_km[:3]]
            + [f"{x:.{VELOCITY_DECIMALS}f}" for x in state_km[3:]])


def lower_triangle(matrix) -> list[list[float]]:
    """Rows of the lower triangle of a 6 x 6 matrix, as the KVN covariance block lists them (row i has i + 1)."""
    matrix = np.asarray(matrix, dtype=float)
    if matrix.shape != (6, 6):
        raise ValueError(f"covariance: need a 6 x 6 matrix, got {matrix.shape}")
    return [list(matrix[i, :i + 1]) for i in range(6)]


def covariance_keys() -> list[str]:
    """The XML element names of the lower triangle, row by row (CX_X, CY_X, CY_Y, ..., CZ_DOT_Z_DOT)."""
    return [f"C{STATE_KEYS[i]}_{STATE_KEYS[j]}" for i in range(6) for j in range(i + 1)]


def _metadata_items(metadata: Metadata) -> list[tuple[str, str]]:
    items = [("OBJECT_NAME", metadata.object_name), ("OBJECT_ID", metadata.object_id),
             ("CENTER_NAME", metadata.center_name), ("REF_FRAME", metadata.ref_frame)]
    if metadata.ref_frame_epoch is not None:
        items.append(("REF_FRAME_EPOCH", metadata.ref_frame_epoch))
    items += [("TIME_SYSTEM", metadata.time_system), ("START_TIME", metadata.start_time),
              ("STOP_TIME", metadata.stop_time)]
    if metadata.interpolation is not None:
        items.append(("INTERPOLATION", metadata.interpolation))
        if metadata.interpolation_degree is not None:
            items.append(("INTERPOLATION_DEGREE", str(metadata.interpolation_degree)))
    return items


def _kvn(metadata, epochs, states_km, originator, covariances, comments, data_comments, created) -> str:
    lines = [f"CCSDS_OEM_VERS = {VERSION}", *(f"COMMENT {c}" for c in comments), f"CREATION_DATE = {created}",
             f"ORIGINATOR = {originator}", "", "META_START", *(f"COMMENT {c}" for c in metadata.comments)]
    lines += [f"{key} = {value}" for key, value in _metadata_items(metadata)]
    lines += ["META_STOP", "", *(f"COMMENT {c}" for c in data_comments)]
    lines += [" ".join([epoch, *state_fields(state)]) for epoch, state in zip(epochs, states_km, strict=True)]
    if covariances:
        lines += ["", "COVARIANCE_START"]
        for cov in covariances:
            lines += [f"EPOCH = {cov.epoch}"] + ([f"COV_REF_FRAME = {cov.ref_frame}"] if cov.ref_frame else [])
            lines += [" ".join(f"{x:.7e}" for x in row) for row in lower_triangle(cov.matrix)]
        lines.append("COVARIANCE_STOP")
    return "\n".join(lines) + "\n"


def _xml(metadata, epochs, states_km, originator, covariances, comments, data_comments, created) -> str:
    root = ElementTree.Element("oem", {"xmlns:xsi": "http://www.w3.org/2001/XMLSchema-instance",
                                       "xsi:noNamespaceSchemaLocation": SCHEMA,
                                       "id": "CCSDS_OEM_VERS", "version": VERSION})

    def add(parent, tag, text=None):
        element = ElementTree.SubElement(parent, tag)
        if text is not None:
            element.text = text
        return element

    header = add(root, "header")
    for c in comments:
        add(header, "COMMENT", c)
    add(header, "CREATION_DATE", created)
    add(header, "ORIGINATOR", originator)
    segment = add(add(root, "body"), "segment")
    meta = add(segment, "metadata")
    for c in metadata.comments:
        add(meta, "COMMENT", c)
    for key, value in _metadata_items(metadata):
        add(meta, key, value)
    data = add(segment, "data")
    for c in data_comments:
        add(data, "COMMENT", c)
    for epoch, state in zip(epochs, states_km, strict=True):
        vector = add(data, "stateVector")
        add(vector, "EPOCH", epoch)
        for key, value in zip(STATE_KEYS, state_fields(state), strict=True):
            add(vector, key, value)
    for cov in covariances:
        matrix = add(data, "covarianceMatrix")
        add(matrix, "EPOCH", cov.epoch)
        if cov.ref_frame:
            add(matrix, "COV_REF_FRAME", cov.ref_frame)
        values = [x for row in lower_triangle(cov.matrix) for x in row]
        for key, value in zip(covariance_keys(), values, strict=True):
            add(matrix, key, f"{value:.7e}")
    ElementTree.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ElementTree.tostring(root, encoding="unicode") + "\n"
