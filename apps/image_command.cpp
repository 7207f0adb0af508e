#include "image_command.h"
#include "emit_text.h"

#include <chrono>
#include <cstring>
#include <sstream>

#include "qm3d/scoring/score.h"
#include "qm3d/common/error.h"
#include "qm3d/common/file_io.h"
#include "qm3d/common/result_io.h"
#include "qm3d/common/version.h"
#include "qm3d/render/icid.h"
#include "qm3d/study/batch_row.h"

namespace qm3d::app {
namespace {

/// The per-pixel map as a NumPy .npy file (version 1.0, little-endian float64, rows x cols).
std::string npy_bytes(const std::vector<double>& values, int rows, int cols) {
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" +
                       std::to_string(rows) + ", " + std::to_string(cols) + "), }";
  constexpr std::size_t kPrefix = 10, kAlign = 64;  // magic, version, header length
  header.append(kAlign - (kPrefix + header.size() + 1) % kAlign, ' ');
  header += '\n';
  std::string out("\x93NUMPY\x01\x00", 8);
  out += static_cast<char>(header.size() & 0xff);
  out += static_cast<char>(header.size() >> 8);
  out += header;
  const std::size_t start = out.size();
  out.resize(start + values.size() * sizeof(double));
  std::memcpy(&out[start], values.data(), values.size() * sizeof(double));  // x86-64, arm64: LE
  return out;
}

MetricResult image_result(const ImageCommand& c, const render::ImageScores& s,
                          const render::IcidOptions& o) {
  MetricResult r;
  r.metric = "image";
  r.score = s.icid.icid;
  r.values.emplace_back("icid", s.icid.icid);
  for (int k = 0; k < 7; ++k) r.values.emplace_back(render::icid_map_names()[k], s.icid.maps[k]);
  r.values.emplace_back("ssim", s.ssim);
  r.values.emplace_back("ms_ssim", s.ms_ssim);
  r.values.emplace_back("psnr", s.psnr);
  r.provenance.version = kVersion;
  r.provenance.reference = c.a;
  r.provenance.distorted = c.b;
  r.provenance.reproduces = render::icid_spec().reproduces;
  r.provenance.options = {{"intent", c.intent},
                          {"iam", o.iam},
                          {"omit_maps67", o.omit_maps67},
                          {"downsampling", o.downsampling}};
  return r;
}

std::string human_line(const render::ImageScores& s) {
  std::ostringstream o;
  o << "iCID = " << short_number(s.icid.icid) << "  SSIM = " << short_number(s.ssim)
    << "  MS-SSIM = " << short_number(s.ms_ssim) << "  PSNR = " << short_number(s.psnr) << " dB\n";
  return o.str();
}

int run_image(const ImageCommand& c, int threads, const std::string& data_dir) {
  const auto start = std::chrono::steady_clock::now();
  check_outputs({{"A", c.a}, {"B", c.b}}, {{"-o", c.output}, {"--map", c.map}});
  const render::RgbImage a = render::read_rgb_image(c.a), b = render::read_rgb_image(c.b);
  if (a.width != b.width || a.height != b.height) {
    throw FormatError(c.b + ": " + std::to_string(b.width) + "x" + std::to_string(b.height) +
                      " pixels, " + c.a + " has " + std::to_string(a.width) + "x" +
                      std::to_string(a.height) + " (the images must have the same size)");
  }
  render::IcidOptions o;
  o.intent = render::icid_intent(c.intent);
  o.iam = !c.no_iam;
  o.omit_maps67 = c.omit_maps67;
  o.downsampling = !c.no_downsampling;
  o.keep_map = !c.map.empty();
  o.threads = threads;
  const auto table = Lab2000hlTable::shared(render::icid_table_dir(data_dir));
  const render::ImageScores s = render::image_scores(a, b, *table, o);
  if (!c.map.empty()) {
    const std::string npy = npy_bytes(s.icid.map, s.icid.map_height, s.icid.map_width);
    write_file_atomically(c.map, [&](std::ostream& out) { out << npy; });
  }
  MetricResult r = image_result(c, s, o);
  r.provenance.seconds = seconds_since(start);
  std::string text;
  if (c.json) {
    text = to_json(r).dump(2) + "\n";
  } else if (c.csv) {
    std::vector<std::string> names;
    for (const auto& [name, value] : r.values) names.push_back(name);
    text = study::csv_header(names) + "\n" + study::csv_row(r, {}, names) + "\n";
  } else {
    text = human_line(s);
  }
  emit_text(text, c.output);
  return 0;
}

}  // namespace

std::unique_ptr<ImageCommand> add_image_command(CLI::App& app,
                                                const std::function<void(CLI::App*)>& add_common) {
  auto c = std::make_unique<ImageCommand>();
  c->cmd = app.add_subcommand(
      "image",
      "Compare two images (8-bit PNG or JPEG, the same size; alpha dropped): iCID (Preiss et "
      "al. 2014, the authors' MATLAB code's numbers; 0 = identical), SSIM and MS-SSIM of the "
      "BT.709 luma, PSNR of R, G, B");
  add_common(c->cmd);
  c->cmd->add_option("A", c->a, "Reference image")->required();
  c->cmd->add_option("B", c->b, "Distorted image")->required();
  c->cmd->add_option("--intent", c->intent, "iCID's prediction intent")
      ->check(CLI::IsMember({"perceptual", "hue-preserving", "chromatic"}))
      ->capture_default_str();
  c->cmd->add_flag("--no-iam", c->no_iam,
                   "iCID without its image-appearance model (the reference's IAM = 'NONE')");
  c->cmd->add_flag("--omit-maps67", c->omit_maps67,
                   "iCID without the chroma contrast and chroma structure maps (Omit_Maps67)");
  c->cmd->add_flag("--no-downsampling", c->no_downsampling,
                   "iCID without its automatic downsampling to ~256 px (Downsampling = false)");
  auto* json = c->cmd->add_flag("--json", c->json, "Write one JSON object");
  c->cmd->add_flag("--csv", c->csv, "Write a CSV header and one row")->excludes(json);
  c->cmd->add_option("-o,--output", c->output, "Write the result to FILE instead of stdout")
      ->type_name("FILE");
  c->cmd
      ->add_option("--map", c->map,
                   "Also write the per-pixel iCID map (1 - the product of the seven terms; the "
                   "(downsampled) image less a 5-pixel border) as NumPy float64")
      ->type_name("FILE.npy");
  return c;
}

std::optional<int> run_image_command(const ImageCommand& c, int threads,
                                     const std::string& data_dir) {
  if (!*c.cmd) return std::nullopt;
  return run_image(c, threads, data_dir);
}

}  // namespace qm3d::app
