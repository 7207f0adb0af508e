// iCID (qm3d/render/icid.h) against the authors' MATLAB code (tests/icid_reference.h: every row
// of shared/data/reference/icid/icid_reference.csv), its properties (identical images, threads),
// the image reader's errors and the registry metric on the reference's stimuli.
#include "qm3d/render/icid.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <thread>

#include "icid_reference.h"
#include "qm3d/common/error.h"
#include "qm3d/mesh/metrics.h"
#include "qm3d/render/ibsm.h"
#include "test_paths.h"

namespace qm3d::render {
namespace {

using test::icid_close;
using test::icid_dir;

const Lab2000hlTable& icid_table() {
  static const Lab2000hlTable t = Lab2000hlTable::load(test::tables_dir() / "icid");
  return t;
}

IcidOptions options_of(const std::string& column) {
  IcidOptions o;
  if (column == "Intent=hue-preserving") o.intent = IcidIntent::kHuePreserving;
  if (column == "Intent=chromatic") o.intent = IcidIntent::kChromatic;
  if (column == "IAM=NONE") o.iam = false;
  if (column == "Omit_Maps67=true") o.omit_maps67 = true;
  if (column == "Downsampling=false") o.downsampling = false;
  return o;
}

std::array<double, 8> values_of(const IcidResult& r) {
  return {r.icid, r.maps[0], r.maps[1], r.maps[2], r.maps[3], r.maps[4], r.maps[5], r.maps[6]};
}

/// iCID of every image row of the table (mean rows left 0), the rows spread over the cores (each
/// on one thread: the same values).
std::vector<std::array<double, 8>> values_of_rows(const std::vector<test::IcidCase>& cases) {
  std::vector<std::array<double, 8>> out(cases.size());
  std::atomic<std::size_t> next{0};
  const auto work = [&] {
    for (std::size_t i = next++; i < cases.size(); i = next++) {
      const auto& c = cases[i];
      if (c.is_mean()) continue;
      IcidOptions o = options_of(c.options);
      o.threads = 1;
      RgbImage a = read_rgb_image(icid_dir() / c.image_a);
      RgbImage b = read_rgb_image(icid_dir() / c.image_b);
      test::read_as_octave(a.rgb);  // the table's reading of the files (icid_reference.h)
      test::read_as_octave(b.rgb);
      out[i] = values_of(icid(a, b, icid_table(), o));
    }
  };
  std::vector<std::thread> workers(std::max(2u, std::thread::hardware_concurrency()) - 1);
  for (auto& w : workers) w = std::thread(work);
  work();
  for (auto& w : workers) w.join();
  return out;
}

TEST(Icid, EveryReferenceRowWithin1e10) {
  const auto cases = test::icid_cases();
  ASSERT_GE(cases.size(), 117u);
  const auto values = values_of_rows(cases);
  std::map<std::string, std::array<double, 8>> set_sums;
  std::map<std::string, int> set_views;
  double worst = 0;
  for (std::size_t row = 0; row < cases.size(); ++row) {
    const auto& c = cases[row];
    std::array<double, 8> got = values[row];
    if (c.is_mean()) {
      ASSERT_GT(set_views[c.set()], 0) << c.name;
      for (int k = 0; k < 8; ++k) got[k] = set_sums[c.set()][k] / set_views[c.set()];
    } else if (!c.set().empty()) {
      for (int k = 0; k < 8; ++k) set_sums[c.set()][k] += got[k];
      ++set_views[c.set()];
    }
    if (std::getenv("QM3D_ICID_DEBUG")) {  // each row's relative differences, to trace a row
      std::cout << c.name << " " << c.options;
      for (int k = 0; k < 8; ++k)
        std::cout << " " << (got[k] - c.values[k]) / std::abs(c.values[k]);
      std::cout << "\n";
    }
    for (int k = 0; k < 8; ++k) {
      EXPECT_PRED2(icid_close, got[k], c.values[k]) << c.name << " " << c.options << " value " << k;
      if (std::abs(c.values[k]) > 1e-9) {
        worst = std::max(worst, std::abs(got[k] - c.values[k]) / std::abs(c.values[k]));
      }
    }
  }
  std::cout << "worst relative difference (values above 1e-9): " << worst << "\n";
}

TEST(Icid, IdenticalImagesScoreZero) {
  const RgbImage a = read_rgb_image(icid_dir() / "synth/synth_noise_a.png");
  for (const char* column : {"default", "IAM=NONE", "Intent=chromatic", "Omit_Maps67=true"}) {
    const IcidResult r = icid(a, a, icid_table(), options_of(column));
    EXPECT_LE(std::abs(r.icid), 1e-13) << column;
    for (double m : r.maps) EXPECT_LE(std::abs(m), 1e-13) << column;
  }
}

TEST(Icid, SameBitsForOneAndTwoThreads) {
  const RgbImage a = read_rgb_image(icid_dir() / "synth/synth_384_rounding_a.png");
  const RgbImage b = read_rgb_image(icid_dir() / "synth/synth_384_rounding_b.png");
  IcidOptions one, two;
  one.threads = 1;
  two.threads = 2;
  one.keep_map = two.keep_map = true;
  const IcidResult r1 = icid(a, b, icid_table(), one), r2 = icid(a, b, icid_table(), two);
  EXPECT_EQ(std::memcmp(&r1.icid, &r2.icid, sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(r1.maps.data(), r2.maps.data(), sizeof(r1.maps)), 0);
  ASSERT_EQ(r1.map.size(), r2.map.size());
  EXPECT_EQ(std::memcmp(r1.map.data(), r2.map.data(), r1.map.size() * sizeof(double)), 0);
  EXPECT_EQ(r1.map_width, 192 - 10);  // 384 -> f = 2 -> 192, less the window's border
}

TEST(Icid, PerPixelMapMeanIsTheScore) {
  const RgbImage a = read_rgb_image(icid_dir() / "synth/synth_blur_a.png");
  const RgbImage b = read_rgb_image(icid_dir() / "synth/synth_blur_b.png");
  IcidOptions o;
  o.keep_map = true;
  const IcidResult r = icid(a, b, icid_table(), o);
  ASSERT_EQ(r.map.size(), static_cast<std::size_t>(r.map_width) * r.map_height);
  double sum = 0;
  for (double v : r.map) sum += v;
  EXPECT_NEAR(sum / static_cast<double>(r.map.size()), r.icid, 1e-12);
}

RgbImage transposed(const RgbImage& in) {
  RgbImage out{in.height, in.width, std::vector<std::uint8_t>(in.rgb.size())};
  for (int y = 0; y < in.height; ++y) {
    for (int x = 0; x < in.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        out.rgb[(static_cast<std::size_t>(x) * out.width + y) * 3 + c] =
            in.rgb[(static_cast<std::size_t>(y) * in.width + x) * 3 + c];
      }
    }
  }
  return out;
}

// Sides whose 3x padding has a large prime factor (3 x 139, 3 x 149) take Bluestein's FFT
// (icid_csf.cpp): the same iCID as the transposed pair (iCID is symmetric under transposition,
// to rounding; rows and columns go through different lengths). (Against kissfft's own generic
// radix on 257 x 383 images, before Bluestein was added: 1.8e-14 relative.)
TEST(Icid, PrimeSidedImagesTransposeInvariant) {
  const RgbImage a = read_rgb_image(icid_dir() / "synth/synth_hue_a.png");
  const RgbImage b = read_rgb_image(icid_dir() / "synth/synth_hue_b.png");
  const auto crop = [](const RgbImage& in, int w, int h) {
    RgbImage out{w, h, {}};
    for (int y = 0; y < h; ++y) {
      const auto* row = &in.rgb[static_cast<std::size_t>(y) * in.width * 3];
      out.rgb.insert(out.rgb.end(), row, row + static_cast<std::size_t>(w) * 3);
    }
    return out;
  };
  const RgbImage pa = crop(a, 149, 139), pb = crop(b, 149, 139);
  const IcidResult r = icid(pa, pb, icid_table());
  const IcidResult t = icid(transposed(pa), transposed(pb), icid_table());
  EXPECT_GT(r.icid, 0.05);
  EXPECT_NEAR(r.icid, t.icid, 1e-12 * r.icid);
  for (int k = 0; k < 7; ++k)
    EXPECT_NEAR(r.maps[k], t.maps[k], 1e-11 * std::abs(r.maps[k]) + 1e-15);
}

TEST(Icid, RejectsDifferentSizesAndTinyImages) {
  const RgbImage a = read_rgb_image(icid_dir() / "synth/synth_blur_a.png");
  const RgbImage b = read_rgb_image(icid_dir() / "synth/synth_noise_a.png");
  EXPECT_THROW(icid(a, b, icid_table()), std::invalid_argument);
  const RgbImage tiny{8, 8, std::vector<std::uint8_t>(8 * 8 * 3, 100)};
  EXPECT_THROW(icid(tiny, tiny, icid_table()), std::invalid_argument);
  const RgbImage short_of_bytes{16, 16, std::vector<std::uint8_t>(16 * 16 * 3 - 1, 100)};
  EXPECT_THROW(icid(short_of_bytes, short_of_bytes, icid_table()), std::invalid_argument);
}

void write_bytes(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary) << bytes;
}

TEST(Icid, ReaderErrorsNameTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / "qm3d_icid_reader_test";
  std::filesystem::create_directories(dir);
  const auto expect_error_naming = [](const std::filesystem::path& p) {
    try {
      read_rgb_image(p);
      ADD_FAILURE() << p << " was read";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    }
  };
  expect_error_naming(dir / "missing.png");
  write_bytes(dir / "text.png", "not an image\n");
  expect_error_naming(dir / "text.png");
  write_bytes(dir / "empty.png", "");
  expect_error_naming(dir / "empty.png");
  write_bytes(dir / "truncated.png", "\x89PNG\r\n\x1a\n\0\0\0\rIHDR");
  expect_error_naming(dir / "truncated.png");
  std::filesystem::remove_all(dir);
}

TEST(Icid, RgbaViewsReadAsRgb) {
  const RgbImage v = read_rgb_image(icid_dir() / "views/blob4_geonoise/view_00_reference.png");
  EXPECT_EQ(v.width, 256);
  EXPECT_EQ(v.rgb.size(), 256u * 256u * 3u);
}

}  // namespace
}  // namespace qm3d::render
