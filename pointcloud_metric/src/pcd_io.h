// Reading PCD files (PCL's Point Cloud Data format, v0.7) without PCL: the header, ascii, binary
// and binary_compressed data.
//
// PCL's I/O library brings VTK, OpenNI, MPI and ~60 shared libraries into every program that
// links it, and they are loaded (and relocated) at each start of the tool, PCD or not. What qm3d
// needs of it is small: x, y, z and a packed colour. So the format is read here, value for value
// as PCL 1.13's PCDReader stores it (tests/pointcloud/pcd_io_test.cpp compares the two on every
// kind of file), and binary_compressed data is decompressed with Debian's liblzf: Marc Lehmann's
// LZF, the algorithm (and code lineage) of PCL's own pcl::lzfCompress.
//
// The layout of a file, as the PCD v0.7 format defines it:
//   header   text lines: FIELDS, SIZE (bytes: 1, 2, 4, 8), TYPE (I, U, F), COUNT (values per
//            field, default 1), WIDTH, HEIGHT, VIEWPOINT, POINTS, then DATA ascii | binary |
//            binary_compressed, the last line of the header
//   ascii    one line per point, COUNT values per field, in FIELDS order
//   binary   POINTS records of sum(SIZE x COUNT) bytes, fields in FIELDS order, little-endian
//   binary_compressed
//            uint32 compressed size, uint32 uncompressed size, then one LZF stream whose
//            content is the fields one after another, each for every point (x0 x1 ... y0 y1 ...)
#pragma once

#include <filesystem>

#include "qm3d/common/types.h"

namespace qm3d::pointcloud::detail {

/// The points of a PCD file as its data stores them.
struct PcdPoints {
  /// #P positions (float or double fields, widened to double; NaN points of organised clouds
  /// kept as NaN) and #P colours from the packed `rgb` / `rgba` field (0x(AA)RRGGBB, declared
  /// F, U or I), each channel u / 255.0; in file order (row by row for organised clouds).
  ColoredCloud cloud;
  /// Whether any of x, y, z is stored as float32 (its rounding may be worth a warning).
  bool float32_coordinates = false;
};

/// Reads a PCD file's points.
/// @throws InputError   the file cannot be opened or read
/// @throws FormatError  a malformed header or data, missing x / y / z, no colour field
///                      ("<file>: no vertex colours ..."): one line, naming the file (and the
///                      line of ascii data)
PcdPoints read_pcd_points(const std::filesystem::path& path);

}  // namespace qm3d::pointcloud::detail
