"""The importer's whole-geometry calls, on shapely 2 or on shapely 1.8.

Shapely 2's vectorized functions where it is installed; else shapely 1.8's (Debian 12's
python3-shapely, which the venv takes on armhf: requirements-nowheel.txt) doing the same
GEOS operations one geometry at a time. Both give the same lines: tests/e2e/
test_debian_geometry.py imports the test drawings with each and compares.
"""

from __future__ import annotations

import numpy as np
import shapely
import shapely.ops
from shapely.geometry import LineString, MultiLineString
from shapely.geometry.base import BaseGeometry, BaseMultipartGeometry

Pieces = list[np.ndarray]
VECTORIZED = hasattr(shapely, "get_parts")      # shapely 2


def union(geoms: list[BaseGeometry]) -> BaseGeometry:
    return shapely.ops.unary_union(geoms)


def faces(edges: BaseGeometry) -> list[BaseGeometry]:
    """The polygons that noded lines split the plane into."""
    return list(shapely.ops.polygonize(parts(edges)))


if VECTORIZED:
    def parts(geom: BaseGeometry) -> list[BaseGeometry]:
        """A multi-part geometry's parts; a single one alone."""
        return list(shapely.get_parts(geom))

    def _merged(geoms) -> list[Pieces]:
        return [[c for c in map(shapely.get_coordinates, shapely.get_parts(g)) if len(c) > 1]
                for g in shapely.line_merge(geoms)]

    def clip_each(pts: np.ndarray, sizes: list[int], area: BaseGeometry) -> list[Pieces]:
        """Each polyline (`sizes` points each of `pts`) inside the area, its pieces joined."""
        index = np.repeat(np.arange(len(sizes)), sizes)
        return _merged(shapely.intersection(shapely.linestrings(pts, indices=index), area))

else:   # shapely 1.8
    def parts(geom: BaseGeometry) -> list[BaseGeometry]:
        """A multi-part geometry's parts; a single one alone."""
        return list(geom.geoms) if isinstance(geom, BaseMultipartGeometry) else [geom]

    def _lines(geom: BaseGeometry) -> list[LineString]:
        if isinstance(geom, BaseMultipartGeometry):
            return [ln for g in geom.geoms for ln in _lines(g)]
        return [geom] if isinstance(geom, LineString) and not geom.is_empty else []

    def _merge(geom: BaseGeometry) -> Pieces:
        lines = _lines(geom)    # what GEOS's line merge takes of a geometry
        if not lines:
            return []
        merged = parts(shapely.ops.linemerge(MultiLineString(lines)))
        return [c for c in (np.asarray(g.coords) for g in merged) if len(c) > 1]

    def _merged(geoms) -> list[Pieces]:
        return [_merge(g) for g in geoms]

    def clip_each(pts: np.ndarray, sizes: list[int], area: BaseGeometry) -> list[Pieces]:
        """Each polyline (`sizes` points each of `pts`) inside the area, its pieces joined."""
        lines = np.split(pts, np.cumsum(sizes)[:-1])
        return _merged(LineString(ln).intersection(area) for ln in lines)


def merged_lines(geom: BaseGeometry) -> Pieces:
    """The lines of a geometry (an intersection's result), joined where they meet."""
    return _merged([geom])[0]
