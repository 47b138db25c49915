// vpm_bench_sampling REGISTERED.vtu --images NAME=IMAGE[,...] [--labels LABELS] --path old|host|device
//   [--level L] [--layout shells|graded] [--shells K] [--samples S] [--out TABLE.tsv] [--json FILE]
//
// One subject sampled the way `vpm sample` does, by one path, with the time of each step and the
// process's peak resident memory (getrusage: run one path per process):
//   old     every sample point held (CanonicalElements::samples), pulled back at once
//           (pull_back_samples), then sample_feature / sample_label_fractions: `vpm sample`
//           before the element sampler;
//   host    ElementSampler on the host threads;
//   device  ElementSampler's kernels on the device VPM_DEVICE selects (ExecutionPlace::device, so
//           PoCL's too, where `vpm sample` would use the host threads).
// The table is written as `vpm sample` writes it (write_subject_table) when --out is given.
// bench/sampling/run.sh runs the paths interleaved and summarises them.
#include <sys/resource.h>

#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "vpm/element_sampler.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/sampling.hpp"
#include "vpm/timing.hpp"

namespace {

const char* kUsage =
    "usage: vpm_bench_sampling REGISTERED.vtu --images NAME=IMAGE[,...] [--labels LABELS] --path old|host|device "
    "[--level L] [--layout shells|graded] [--shells K] [--samples S] [--out TABLE.tsv] [--json FILE]";

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // kB on Linux
}

std::map<std::string, std::string> parse(int argc, char** argv) {
  std::map<std::string, std::string> a;
  for (int i = 2; i < argc; ++i) {
    const std::string k = argv[i];
    if (k.rfind("--", 0) != 0 || i + 1 >= argc) throw vpm::InputError(kUsage);
    a[k] = argv[++i];
  }
  if (argc < 2 || !a.count("--path") || (!a.count("--images") && !a.count("--labels"))) throw vpm::InputError(kUsage);
  return a;
}

vpm::ElementDefinition definition(std::map<std::string, std::string>& a) {
  vpm::ElementDefinition d;
  d.level = std::stoi(a.count("--level") ? a["--level"] : "3");
  d.layout = vpm::parse_element_layout(a.count("--layout") ? a["--layout"] : "shells");
  d.shells = d.layout == vpm::ElementLayout::graded ? vpm::graded_shells(d.level)
                                                      : std::stoi(a.count("--shells") ? a["--shells"] : "8");
  d.samples = std::stoi(a.count("--samples") ? a["--samples"] : "64");
  return d;
}

// The subject's images: the feature images (NAME=IMAGE,...), then the label image if any.
struct Images {
  std::vector<std::string> names;
  std::vector<vpm::Image> images;
  bool labels = false;
};

Images read_images(std::map<std::string, std::string>& a) {
  Images out;
  std::stringstream ss(a["--images"]);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) throw vpm::InputError(kUsage);
    out.names.push_back(item.substr(0, eq));
    out.images.push_back(vpm::read_image(item.substr(eq + 1)));
  }
  if (a.count("--labels")) {
    out.images.push_back(vpm::read_image(a["--labels"]));
    out.labels = true;
  }
  return out;
}

// `vpm sample` before the element sampler.
void sample_old(const vpm::CanonicalElements& el, const vpm::TetMesh& mesh, const vpm::Points& native,
                const Images& im, vpm::ElementTable& t, vpm::Json& steps) {
  vpm::Stopwatch sw;
  el.samples();
  steps["samples_s"] = sw.seconds();
  steps["samples_cpu_s"] = sw.cpu_seconds();
  sw.restart();
  const vpm::Points pos = vpm::pull_back_samples(el, mesh.vertices, mesh.tets, native);
  steps["pull_back_s"] = sw.seconds();
  steps["pull_back_cpu_s"] = sw.cpu_seconds();
  sw.restart();
  for (size_t k = 0; k < im.names.size(); ++k) t.features.push_back(vpm::sample_feature(el, pos, im.images[k], im.names[k]));
  if (im.labels) t.label_images.push_back(vpm::sample_label_fractions(el, pos, im.images.back()));
  steps["read_images_s"] = sw.seconds();
  steps["read_images_cpu_s"] = sw.cpu_seconds();
}

void sample_new(const vpm::CanonicalElements& el, const vpm::TetMesh& mesh, const vpm::Points& native,
                const Images& im, vpm::Device& device, vpm::ElementTable& t, vpm::Json& steps) {
  vpm::Stopwatch sw;
  vpm::ElementSamplerOptions options;
  options.place = vpm::ExecutionPlace::device;  // the kernels on any OpenCL device, the host's threads on the host
  const vpm::ElementSampler sampler(el, mesh.vertices, mesh.tets, native, device, options);
  steps["prepare_s"] = sw.seconds();
  sw.restart();
  std::vector<vpm::NamedImage> features;
  for (size_t k = 0; k < im.names.size(); ++k) features.push_back({im.names[k], &im.images[k]});
  std::vector<const vpm::Image*> labels;
  if (im.labels) labels.push_back(&im.images.back());
  vpm::ElementTable s = sampler.sample(features, labels);
  t.features = std::move(s.features);
  t.label_images = std::move(s.label_images);
  steps["sample_s"] = sw.seconds();
  steps["sample_cpu_s"] = sw.cpu_seconds();
  steps["placement"] = vpm::to_json(sampler.placement());
}

}  // namespace

int main(int argc, char** argv) try {
  auto a = parse(argc, argv);
  const std::string path = a["--path"];
  if (path != "old" && path != "host" && path != "device") throw vpm::InputError(kUsage);
  vpm::Json j = vpm::Json::object(), steps = vpm::Json::object();
  vpm::Stopwatch total, sw;
  const vpm::TetMesh mesh = vpm::read_mesh(argv[1]);
  const vpm::Points native = vpm::native_positions(mesh, argv[1]);
  const Images im = read_images(a);
  steps["read_inputs_s"] = sw.seconds();
  sw.restart();
  vpm::ElementTable t;
  t.definition = definition(a);
  t.mesh = argv[1];
  const vpm::CanonicalElements el(t.definition);
  steps["elements_s"] = sw.seconds();
  if (path == "old") sample_old(el, mesh, native, im, t, steps);
  else sample_new(el, mesh, native, im, path == "host" ? *vpm::Device::host() : vpm::Device::current(), t, steps);
  sw.restart();
  if (a.count("--out")) vpm::write_subject_table(a["--out"], t);
  steps["write_s"] = sw.seconds();
  steps["write_cpu_s"] = sw.cpu_seconds();
  j["path"] = path;
  j["mesh"] = argv[1];
  j["tets"] = mesh.num_tets();
  j["definition"] = vpm::to_json(t.definition);
  j["elements"] = el.size();
  j["steps"] = steps;
  j["total_s"] = total.seconds();
  j["total_cpu_s"] = total.cpu_seconds();
  j["peak_rss_mb"] = peak_rss_mb();
  std::printf("%s\n", j.dump(2).c_str());
  if (a.count("--json")) vpm::write_json_file(a["--json"], j);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "vpm_bench_sampling: %s\n", e.what());
  return 2;
}
