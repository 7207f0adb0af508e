// Reading coloured point clouds: PLY (through qm3d::ply) and PCD (qm3d's own reader, which reads
// what PCL 1.13's PCDReader reads, without linking PCL), chosen by the file extension.
#pragma once

#include <filesystem>

#include "qm3d/common/reading.h"
#include "qm3d/common/types.h"

namespace qm3d::pointcloud {

/// Reads a coloured point cloud; the format is chosen by the extension, case-insensitively.
///
/// - `.ply`: ASCII or binary (either endianness); x, y, z of any scalar type (float or double
///   keep their exact value); colours uchar, ushort or float named red/green/blue, r/g/b or
///   diffuse_red/green/blue (see qm3d/common/ply.h). Faces, normals and alpha are ignored.
/// - `.pcd`: ascii, binary or binary_compressed; fields x, y, z (float or double) and a packed
///   `rgb` or `rgba` field (float or uint32 holding 0x00RRGGBB / 0xAARRGGBB; without one, no
///   colours, as a colourless PLY: read_cloud refuses it, psnr --no-color takes it), each of COUNT
///   1 (other fields may have any COUNT: a field of COUNT n takes n ASCII columns). An ASCII line
///   with a value too many or too few, data beyond POINTS or fewer points than it, a binary file
///   whose size is not POINTS records, compressed data whose sizes disagree with POINTS or whose
///   LZF stream is corrupt are FormatErrors naming the file (and the line). Points with a NaN or
///   infinite coordinate (the invalid pixels of an organised, `is_dense false` cloud) are
///   dropped as pcl::removeNaNFromPointCloud drops them, with one warning giving their count
///   (read_cloud_data); a cloud with no valid point is a FormatError naming the file.
///
/// Colours are returned in [0, 1] at double precision; an 8-bit channel u becomes u / 255.0,
/// exactly as MEPP-team/PCQM converts its colours.
///
/// @param[in] path  file to read
/// @return #P positions and #P colours, in file order
/// @throws InputError   the file cannot be opened or read
/// @throws FormatError  unknown extension, malformed content, or no colours
///                      ("<file>: no vertex colours ...")
///
/// Numbers are parsed the same whatever the C locale. The reader's warnings (read_cloud_data)
/// are dropped here.
///
/// \bug OBJ and OFF meshes are not read here (the mesh reader will provide their vertices).
ColoredCloud read_cloud(const std::filesystem::path& path);

enum class CloudFormat { kPly, kPcd };
/// read_cloud with the format given (e.g. recognised by content) instead of the extension.
ColoredCloud read_cloud(const std::filesystem::path& path, CloudFormat format);

/// read_cloud with the reader's options (the scale of PLY float colours) and its warnings: a
/// colour scale chosen on thin evidence, float32 coordinates whose rounding is large against
/// the point spacing (qm3d/common/reading.h). What the metric registry's cloud reader returns.
/// Unlike read_cloud, a PLY without colours gives a cloud without colours (and a PLY's nx, ny,
/// nz are kept in CloudData::normals).
CloudData read_cloud_data(const std::filesystem::path& path, CloudFormat format,
                          const ReadOptions& options = {});

/// FormatError "<name>: no vertex colours (PCQM needs ...)" when a non-empty cloud has none.
void require_colours(const ColoredCloud& cloud, const std::string& name);

}  // namespace qm3d::pointcloud
