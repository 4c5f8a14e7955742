#!/usr/bin/env python3
"""Checks drape's VTU output with an independent reader (meshio).

Reads a ParaView series (.pvd) or single .vtu files and checks every frame's
point and cell counts and that the named arrays are present with one entry
per point or cell; when the `vtk` package is installed too, VTK's own XML
reader (ParaView's) checks the same files. drape writes its VTU files by hand, so this is the check
that a real reader agrees with the writer (drape-io's tests call it when
meshio is installed; .ci/run installs it).

Usage:
    python3 tests/check_vtu.py OUT/series.pvd --points 441 --cells 400 \
        --point-data displacement,velocity --cell-data shear_angle_deg \
        [--frames 2] [--cell-type quad] [--fibres-vs-shear 1e-9]
    python3 tests/check_vtu.py OUT/trusses.pvd --cell-type line \
        --cell-data family,tension,tension_per_width,stretch --truss-stretch
    python3 tests/check_vtu.py OUT/tools.pvd --cell-type triangle \
        --cell-data tool --shift 0,0,12.5

The content checks, computed here from what meshio reads:
  --fibres-vs-shear TOL  fibre_direction_warp/_weft are 3-component unit
                         vectors (to 1e-12) and the angle between them is
                         90 deg minus shear_angle_deg, to TOL degrees;
  --truss-stretch        each line cell's `stretch` is its length over its
                         length in the series' first frame (to 1e-9);
  --shift X,Y,Z          the last frame's points are the first frame's moved
                         by (X, Y, Z) (to 1e-9 mm).

Exit status 0 when every check passes, 1 with one line per failure
otherwise, 2 on bad usage.
"""

import argparse
import math
import os
import sys
import xml.etree.ElementTree as ET


def frames_of(path):
    """(time or None, vtu path) of each frame a .pvd or .vtu path names."""
    if not path.endswith(".pvd"):
        return [(None, path)]
    root = ET.parse(path).getroot()
    if root.get("type") != "Collection":
        raise ValueError(f"{path}: VTKFile type is {root.get('type')!r}, not 'Collection'")
    base = os.path.dirname(path)
    frames = []
    for dataset in root.iter("DataSet"):
        frames.append((float(dataset.get("timestep")), os.path.join(base, dataset.get("file"))))
    return frames


def names(text):
    return [n for n in (text or "").split(",") if n]


def check_frame(meshio, path, args):
    """The failures of one .vtu file, as messages."""
    failures = []
    mesh = meshio.read(path)
    n_points = len(mesh.points)
    n_cells = sum(len(block.data) for block in mesh.cells)
    if args.points is not None and n_points != args.points:
        failures.append(f"{path}: {n_points} points, expected {args.points}")
    if args.cells is not None and n_cells != args.cells:
        failures.append(f"{path}: {n_cells} cells, expected {args.cells}")
    for name in names(args.point_data):
        if name not in mesh.point_data:
            failures.append(f"{path}: no point data {name!r} (has {sorted(mesh.point_data)})")
        elif len(mesh.point_data[name]) != n_points:
            failures.append(f"{path}: point data {name!r} has {len(mesh.point_data[name])} entries")
    for name in names(args.cell_data):
        if name not in mesh.cell_data:
            failures.append(f"{path}: no cell data {name!r} (has {sorted(mesh.cell_data)})")
            continue
        per_block = [len(values) for values in mesh.cell_data[name]]
        if sum(per_block) != n_cells:
            failures.append(f"{path}: cell data {name!r} has {sum(per_block)} entries for {n_cells} cells")
    if args.cell_type is not None:
        types = sorted({block.type for block in mesh.cells})
        if types != [args.cell_type]:
            failures.append(f"{path}: cell types {types}, expected only {args.cell_type!r}")
    if args.fibres_vs_shear is not None:
        failures.extend(check_fibres(mesh, path, args.fibres_vs_shear))
    return failures


def cell_array(mesh, name):
    """The cell array `name` over every block, as one list of rows (a number
    per cell for a one-component array, which meshio may read as n x 1)."""
    rows = []
    for values in mesh.cell_data[name]:
        rows.extend(v[0] if isinstance(v, list) and len(v) == 1 else v for v in values.tolist())
    return rows


def check_fibres(mesh, path, tol_deg):
    """Unit fibre vectors whose angle is 90 deg minus the shear angle."""
    failures = []
    try:
        warp = cell_array(mesh, "fibre_direction_warp")
        weft = cell_array(mesh, "fibre_direction_weft")
        shear = cell_array(mesh, "shear_angle_deg")
    except KeyError as e:
        return [f"{path}: no cell data {e}"]
    worst = (0.0, None)
    for i, (w, f, g) in enumerate(zip(warp, weft, shear)):
        if len(w) != 3 or len(f) != 3:
            failures.append(f"{path}: cell {i}: fibre directions of {len(w)} and {len(f)} components")
            break
        for name, v in (("warp", w), ("weft", f)):
            norm = math.sqrt(sum(c * c for c in v))
            if abs(norm - 1.0) > 1e-12:
                failures.append(f"{path}: cell {i}: |{name}| = {norm!r}, not a unit vector")
        cos = max(-1.0, min(1.0, sum(a * b for a, b in zip(w, f))))
        error = abs(math.degrees(math.acos(cos)) - (90.0 - g))
        if error > worst[0]:
            worst = (error, i)
    if worst[0] > tol_deg:
        failures.append(
            f"{path}: cell {worst[1]}: acos(warp . weft) differs from 90 - shear by "
            f"{worst[0]:.3e} deg (tolerance {tol_deg:.1e})"
        )
    else:
        print(f"{path}: acos(warp . weft) = 90 - shear to {worst[0]:.3e} deg over {len(shear)} cells")
    return failures


def line_lengths(mesh):
    """The length of every line cell, in block order."""
    lengths = []
    for block in mesh.cells:
        for a, b in block.data.tolist():
            p, q = mesh.points[a], mesh.points[b]
            lengths.append(math.sqrt(sum((x - y) ** 2 for x, y in zip(p, q))))
    return lengths


def check_series(meshio, frames, args):
    """Checks across the frames of one series: the trusses' stretch against
    their lengths in the first frame, a rigid shift of the points."""
    failures = []
    if len(frames) < 1 or (args.shift is None and not args.truss_stretch):
        return failures
    first = meshio.read(frames[0][1])
    last = meshio.read(frames[-1][1])
    if args.truss_stretch:
        reference = line_lengths(first)
        for _, path in frames:
            mesh = meshio.read(path)
            stretch = cell_array(mesh, "stretch")
            for i, (l, l0, s) in enumerate(zip(line_lengths(mesh), reference, stretch)):
                if abs(l / l0 - s) > 1e-9:
                    failures.append(f"{path}: line {i}: stretch {s!r}, its length ratio {l / l0!r}")
                    break
    if args.shift is not None:
        shift = [float(c) for c in args.shift.split(",")]
        if len(first.points) != len(last.points):
            failures.append("first and last frames differ in their points")
        else:
            worst = max(
                (abs(q[k] - p[k] - shift[k]) for p, q in zip(first.points, last.points) for k in range(3)),
                default=0.0,
            )
            if worst > 1e-9:
                failures.append(f"{frames[-1][1]}: points not moved by {shift}: off by {worst:.3e} mm")
    return failures


def check_frame_with_vtk(vtk, path, args):
    """The failures of one .vtu file read by VTK's own XML reader (used when
    the `vtk` package happens to be installed: it is the reader ParaView
    uses, stricter than meshio)."""
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    failures = []
    if args.points is not None and grid.GetNumberOfPoints() != args.points:
        failures.append(f"{path}: VTK reads {grid.GetNumberOfPoints()} points, expected {args.points}")
    if args.cells is not None and grid.GetNumberOfCells() != args.cells:
        failures.append(f"{path}: VTK reads {grid.GetNumberOfCells()} cells, expected {args.cells}")
    for kind, data in (("point", grid.GetPointData()), ("cell", grid.GetCellData())):
        wanted = names(args.point_data if kind == "point" else args.cell_data)
        for name in wanted:
            if data.GetArray(name) is None:
                failures.append(f"{path}: VTK finds no {kind} data {name!r}")
    return failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("paths", nargs="+", help=".pvd series or .vtu files")
    parser.add_argument("--points", type=int, help="expected number of points in every frame")
    parser.add_argument("--cells", type=int, help="expected number of cells in every frame")
    parser.add_argument("--point-data", default="", help="comma-separated point array names")
    parser.add_argument("--cell-data", default="", help="comma-separated cell array names")
    parser.add_argument("--frames", type=int, help="expected number of frames over all paths")
    parser.add_argument("--cell-type", help="the only meshio cell type expected (quad, triangle, line)")
    parser.add_argument("--fibres-vs-shear", type=float, metavar="TOL_DEG",
                        help="check the fibre vectors against the shear angle")
    parser.add_argument("--truss-stretch", action="store_true",
                        help="check the lines' stretch against their first-frame lengths")
    parser.add_argument("--shift", metavar="X,Y,Z", help="the last frame's points are the first's moved by this")
    args = parser.parse_args()

    try:
        import meshio
    except ImportError:
        print("check_vtu.py: meshio is not installed (pip install meshio)", file=sys.stderr)
        return 2

    try:
        import vtk
    except ImportError:
        vtk = None

    failures = []
    frames = []
    for path in args.paths:
        try:
            frames.extend(frames_of(path))
        except (OSError, ET.ParseError, ValueError, TypeError) as e:
            failures.append(f"{path}: {e}")
    times = [t for t, _ in frames if t is not None]
    if any(b < a for a, b in zip(times, times[1:])):
        failures.append(f"series times decrease: {times}")
    if args.frames is not None and len(frames) != args.frames:
        failures.append(f"{len(frames)} frames, expected {args.frames}")
    for _, path in frames:
        try:
            failures.extend(check_frame(meshio, path, args))
        except Exception as e:  # a reader error is a failed check, not a crash
            failures.append(f"{path}: meshio cannot read it: {type(e).__name__}: {e}")
        if vtk is not None:
            failures.extend(check_frame_with_vtk(vtk, path, args))
    try:
        failures.extend(check_series(meshio, frames, args))
    except Exception as e:  # as above
        failures.append(f"series check: {type(e).__name__}: {e}")

    for failure in failures:
        print(f"FAIL {failure}")
    if failures:
        return 1
    readers = f"meshio {meshio.__version__}" + (f" and VTK {vtk.vtkVersion.GetVTKVersion()}" if vtk else "")
    print(f"ok: {len(frames)} frame(s) read by {readers}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
