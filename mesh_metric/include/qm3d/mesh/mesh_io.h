// Reading coloured triangle meshes: OBJ (`v x y z r g b`), OFF / COFF (RGB or RGBA, comments),
// PLY (ASCII and binary, both endians; colours uchar, ushort or float).
//
// Colour ranges follow MEPP2's reader where the format is ambiguous (SPEC-CMDM 1.2): OBJ and OFF
// colours (and PLY float colours) are read as 0..1 unless any value of the file exceeds 1, in
// which case every value is c -> floor(c + 0.5) / 255; a decision resting on few values is
// reported as a warning, and MeshReadOptions::colour_scale overrides the rule (reading.h).
// PLY integer colours use the range their type says. Like MEPP2, colours are kept at float
// precision, so that scores match the reference to ~1e-10.
// OBJ vertices: `v x y z`, `v x y z w` (w ignored) or `v x y z r g b`; other counts are errors.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "qm3d/common/reading.h"
#include "qm3d/common/types.h"

namespace qm3d::mesh {

/// A mesh read from a file, with what the reader changed on the way.
struct MeshFile {
  ColoredMesh mesh;
  /// One line per repair or caveat: polygons fan-triangulated, unreferenced vertices dropped,
  /// a colour scale chosen on thin evidence, float32 coordinates rounded against their spacing.
  std::vector<std::string> warnings;
  /// For each vertex of `mesh`, its index in the file (differs only when vertices were dropped).
  std::vector<std::uint32_t> file_vertex;
};

struct MeshReadOptions {
  /// A mesh without vertex colours is an error (CMDM, PCQM) unless this is false (MSDM2); then
  /// `colors` is left empty. Colours on only some vertices are always an error.
  bool require_colors = true;
  /// The scale of colours stored as numbers (OBJ, OFF, PLY float); kAuto = MEPP2's rule.
  ColourScale colour_scale = ColourScale::kAuto;
};

/// Reads a mesh, dispatching on the extension (.obj, .off, .ply; case-insensitive).
///
/// Throws InputError (missing / unreadable path) or FormatError naming the file: unknown
/// extension, malformed content, face index out of range, no vertex colours or colours on only
/// some vertices, colour values outside [0, 255], no faces.
/// An OBJ with an `mtllib` and no vertex colours is read as a textured mesh: its vertex colours
/// are sampled from the texture (texture.h; errors for a missing MTL / texture, missing UVs or
/// an undecodable image). With `require_colors == false` the texture is not read.
MeshFile read_mesh(const std::filesystem::path& path, const MeshReadOptions& options = {});

/// The text and binary formats read_mesh understands.
enum class MeshFormat { kObj, kOff, kPly };

/// Parses a mesh already in memory (what read_mesh does after reading the file); `name` names
/// it in messages.
MeshFile parse_mesh(const std::string& bytes, MeshFormat format, const std::string& name,
                    const MeshReadOptions& options = {});

/// Reads only the vertices (positions and colours) of any mesh format; faces may be absent.
/// Used to read a mesh as a point cloud.
ColoredCloud read_mesh_vertices(const std::filesystem::path& path);

/// A mesh given as arrays (e.g. from Python), made what read_mesh would have made of a file
/// holding them: indices checked, colours (empty = none; else one per vertex in [0, 1]) kept at
/// float precision, vertices no face uses dropped (with a warning). `name` names the mesh in
/// errors. FormatError for bad indices or colours, NumericError for non-finite coordinates.
MeshFile mesh_from_arrays(std::vector<Vec3> positions, std::vector<Rgb> colors,
                          std::vector<Triangle> triangles, const std::string& name);

/// read_mesh and read_mesh_vertices with the format given (e.g. recognised by content,
/// qm3d/common/metric.h) instead of taken from the extension.
MeshFile read_mesh(const std::filesystem::path& path, MeshFormat format,
                   const MeshReadOptions& options = {});
ColoredCloud read_mesh_vertices(const std::filesystem::path& path, MeshFormat format);
/// read_mesh_vertices with the colour scale of `options` and the reader's warnings.
CloudData read_mesh_vertices_data(const std::filesystem::path& path, MeshFormat format,
                                  const ReadOptions& options = {});

}  // namespace qm3d::mesh
