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
        [--frames 2]

Exit status 0 when every check passes, 1 with one line per failure
otherwise, 2 on bad usage.
"""

import argparse
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

    for failure in failures:
        print(f"FAIL {failure}")
    if failures:
        return 1
    readers = f"meshio {meshio.__version__}" + (f" and VTK {vtk.vtkVersion.GetVTKVersion()}" if vtk else "")
    print(f"ok: {len(frames)} frame(s) read by {readers}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
