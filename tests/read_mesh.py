"""Opens one mesh file sere wrote with VTK's own readers (Debian's python3-vtk9), the code
ParaView runs, and prints what they read as one line for tests/test_readers.c to check.
Run as /usr/bin/python3 tests/read_mesh.py FILE; the line is one of

  mesh POINTS POLYS TRIANGLES GEOMETRY NAME=TUPLES,COMPONENTS,NONFINITE,MIN,MAX,FRACTIONAL ...
      for a .ply (vtkPLYReader) or a .vtp (vtkXMLPolyDataReader): the point and polygon counts,
      how many polygons are triangles, a CRC-32 of the points (float32) and triangle corners
      (int64) that is equal for a PLY and a VTP of the same mesh, then each point-data array
  pvd COUNT FILE@TIME:POINTS:POLYS ...
      for a .pvd (ParaView's collection, which VTK alone has no reader for: parsed with xml and
      every dataset it lists opened with vtkXMLPolyDataReader), in the file's order
  error PATH: MESSAGE
      when a reader failed or said anything; the exit status is then 1

vtkPLYReader of VTK 9.1 reads only the standard PLY properties (coordinates, normals, colors,
texture coordinates), so a PLY's own float properties are not among its arrays: the C test
compares the PLY's geometry digest with the VTP's, which a header whose property list disagrees
with the binary body does not match (the reader steps over each vertex by the header's size).
"""

import math
import os
import struct
import sys
import xml.etree.ElementTree as ElementTree
import zlib

# No numpy: python3-vtk9 does not depend on it, and these meshes are small.
from vtkmodules.vtkCommonCore import vtkLogger, vtkOutputWindow, vtkStringOutputWindow
from vtkmodules.vtkIOPLY import vtkPLYReader
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader


class ReaderError(Exception):
    pass


# A reader reports trouble through VTK's output window (and loguru on stderr), not through an
# exception or always through its error code: collect the window's text and call any of it a
# failure, since a file ParaView warns about is not one a user can trust.
messages = vtkStringOutputWindow()
vtkOutputWindow.SetInstance(messages)
vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)


def read(reader_class, path):
    reader = reader_class()
    reader.SetFileName(path)
    reader.Update()
    said = " ".join(messages.GetOutput().split())
    if said or reader.GetErrorCode() != 0:
        raise ReaderError(f"{reader_class.__name__}: {said or 'error code %d' % reader.GetErrorCode()}")
    return reader.GetOutput()


def values(array):
    return [array.GetValue(k) for k in range(array.GetNumberOfValues())]


def array_summary(name, array):
    every = values(array)
    finite = [value for value in every if math.isfinite(value)]
    return "%s=%d,%d,%d,%.9g,%.9g,%d" % (
        name,
        array.GetNumberOfTuples(),
        array.GetNumberOfComponents(),
        len(every) - len(finite),
        min(finite, default=math.nan),
        max(finite, default=math.nan),
        sum(1 for value in finite if value != math.floor(value)),
    )


def mesh_line(reader_class, path):
    mesh = read(reader_class, path)
    polys = mesh.GetPolys()
    offsets = values(polys.GetOffsetsArray())
    corners = values(polys.GetConnectivityArray())
    triangles = sum(1 for k in range(len(offsets) - 1) if offsets[k + 1] - offsets[k] == 3)
    xyz = values(mesh.GetPoints().GetData()) if mesh.GetPoints() is not None else []
    digest = zlib.crc32(struct.pack("<%dq" % len(corners), *corners), zlib.crc32(struct.pack("<%df" % len(xyz), *xyz)))
    data = mesh.GetPointData()
    arrays = [array_summary(data.GetArrayName(k), data.GetArray(k)) for k in range(data.GetNumberOfArrays())]
    return " ".join(
        ["mesh", str(mesh.GetNumberOfPoints()), str(polys.GetNumberOfCells()), str(triangles), "%08x" % digest]
        + arrays
    )


def pvd_line(path):
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError as error:
        raise ReaderError(f"xml: {error}")
    datasets = root.findall("./Collection/DataSet")
    if root.get("type") != "Collection" or not datasets:
        raise ReaderError("not a VTKFile of type Collection with DataSet entries")
    fields = ["pvd", str(len(datasets))]
    for dataset in datasets:
        name, time = dataset.get("file"), dataset.get("timestep")
        if name is None or time is None:
            raise ReaderError("a DataSet without file or timestep")
        try:
            mesh = read(vtkXMLPolyDataReader, os.path.join(os.path.dirname(path), name))
        except ReaderError as error:
            raise ReaderError(f"dataset {name}: {error}")
        fields.append("%s@%s:%d:%d" % (name, time, mesh.GetNumberOfPoints(), mesh.GetNumberOfPolys()))
    return " ".join(fields)


def main(path):
    kind = os.path.splitext(path)[1]
    try:
        if kind == ".ply":
            print(mesh_line(vtkPLYReader, path))
        elif kind == ".vtp":
            print(mesh_line(vtkXMLPolyDataReader, path))
        elif kind == ".pvd":
            print(pvd_line(path))
        else:
            raise ReaderError("not a .ply, .vtp or .pvd")
    except ReaderError as error:
        print(f"error {path}: {error}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
