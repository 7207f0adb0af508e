// Textured meshes (OBJ + MTL + texture map; PLY with texture coordinates and `comment
// TextureFile`; maps in PNG, JPEG, BMP or TGA): texture colours transferred to the vertices, as the
// CMDM paper scored textured meshes (seed document 1.3.4), and kept with their UVs for surface
// sampling.
//
// Conventions: UV (0, 0) is the bottom-left corner of the image, (1, 1) the top-right (OBJ);
// texel (i, j) is centred at ((i + 0.5) / W, 1 - (j + 0.5) / H); lookups are bilinear between
// the four nearest texel centres and wrap around (MTL's default `-clamp off`).
// A vertex with several UVs (a texture seam) gets the average of the bilinear samples at its
// distinct UVs. A material without `map_Kd` uses its `Kd` colour everywhere.
//
// \bug Only `map_Kd` (diffuse) is read; its options (-o, -s, -clamp, ...) are not supported.
#pragma once

#include <array>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qm3d/common/grid_samples.h"
#include "qm3d/common/reading.h"
#include "qm3d/common/types.h"
#include "qm3d/mesh/mesh_io.h"

namespace qm3d::mesh {

/// A texture coordinate (u, v), u to the right, v upwards, one period per unit.
using Uv = std::array<double, 2>;

/// An RGB image with sRGB channels in [0, 1]; texels row-major, row 0 the top row of the file.
struct TextureImage {
  int width = 0;
  int height = 0;
  std::vector<Rgb> texels;  ///< #width*#height
};

/// Reads a PNG, JPEG, BMP or TGA image (8-bit, any channel count; alpha ignored, grey
/// expanded), through stb_image, with the same limits for every format: at most
/// kMaxTextureBytes of file (file_io.h) and kMaxTextureTexels texels. Throws InputError when
/// the file is missing, FormatError naming it when the image cannot be decoded or is too large.
TextureImage read_texture(const std::filesystem::path& path);
/// 16384 x 16384: the largest texture of common GPUs, an image of 6 GiB once decoded here.
inline constexpr long long kMaxTextureTexels = 16384LL * 16384LL;

/// Bilinear, wrapping lookup of `image` at `uv` (conventions above).
Rgb sample_texture(const TextureImage& image, const Uv& uv);

/// mmetric's 8-bit value of a colour channel held in [0, 1] (u / 255 for 8-bit sources, an OBJ's
/// float): roundf((float)c * 255), as it reads OBJ and PLY colours and texels.
inline float mm_channel_255(double c) { return std::round(static_cast<float>(c) * 255.0f); }

/// mmetric 1.1.7's lookup of `image` at float (u, v) (mmImage.h texture2D / texture2D_bilinear):
/// nearest (texel floor(u W), floor(v H)) or bilinear between the four nearest texel centres,
/// edges clamped (no wrap), v = 0 the bottom row; channels 0..255, each texel roundf(c * 255).
/// What its grid sampling and its software renderer colour with.
Float3 mm_texture_lookup(const TextureImage& image, float u, float v, bool bilinear);

/// A mesh whose colours come from textures.
struct TexturedMesh {
  /// The mesh as read_mesh returns it; its vertex colours are the texture colours (above).
  MeshFile file;
  std::vector<Uv> uvs;                          ///< every `vt` of the file
  std::vector<Triangle> triangle_uvs;           ///< #F: for each corner, an index into `uvs`
  std::vector<std::uint32_t> triangle_texture;  ///< #F: an index into `textures`
  std::vector<TextureImage> textures;           ///< one per material
};

/// True when `obj_text` is an OBJ whose colours come from materials: it names an `mtllib` and
/// no vertex carries an `r g b` colour.
bool obj_is_textured(const std::string& obj_text);

/// Reads an OBJ with its MTL and textures (paths relative to the file that names them).
/// Throws InputError / FormatError naming the file at fault: missing MTL or texture file, an
/// undecodable image, a face without UVs or without a material, an unknown material.
TexturedMesh read_textured_obj(const std::filesystem::path& path);

/// The same for an OBJ already read into `obj_text`; `path` locates its MTL and textures.
TexturedMesh parse_textured_obj(const std::string& obj_text, const std::filesystem::path& path);

/// The one texture image the faces of an OBJ use (the `map_Kd` of their materials, as
/// read_textured_obj finds it), for metrics that take a single texture per mesh (GeodesicPSIM).
/// FormatError naming the file at fault: no mtllib, a face without UV or material, a material
/// without `map_Kd`, materials naming different images, a missing MTL or map.
std::filesystem::path obj_texture_file(const std::string& obj_text,
                                       const std::filesystem::path& path);

/// The textured mesh of a mesh file (`bytes`, its content; `path` locates its maps) whose
/// colours come from texture maps, or nothing when they do not:
/// - OBJ: an `mtllib` and no vertex colours (obj_is_textured), or texture coordinates (`vt`);
/// - PLY: texture coordinates per vertex (texture_u / texture_v, s / t or u / v) or per corner
///   (face list `texcoord`), maps from `comment TextureFile NAME` lines (relative to the PLY;
///   a face's `texnumber` picks one, 0 without it).
/// `options.texture`, when given, replaces every map: every face with texture coordinates takes
/// its colour from it (mmetric's --inputMapA / --inputMapB with one map).
/// A mesh with texture coordinates but no usable texture (no mtllib or TextureFile, a material
/// or map file that is not there, an undefined material) gives nothing and one warning naming
/// the file, the reason and options.texture_option, added to `warnings` (when not null).
/// Throws FormatError / InputError naming the file for an image that cannot be decoded, a given
/// map that is not there, or malformed texture coordinates.
/// The words of read_textured_mesh's warning that a mesh is read without its texture.
inline constexpr const char* kReadWithoutTexture = "read without its texture";

/// False when the file certainly is not a textured mesh (an OFF; a PLY whose header declares no
/// texture coordinates, with no map given): read_textured_mesh need not read it.
bool may_be_textured(const std::filesystem::path& path, MeshFormat format,
                     const ReadOptions& options);

std::optional<TexturedMesh> read_textured_mesh(const std::string& bytes, MeshFormat format,
                                               const std::filesystem::path& path,
                                               const ReadOptions& options,
                                               std::vector<std::string>* warnings = nullptr);

}  // namespace qm3d::mesh
