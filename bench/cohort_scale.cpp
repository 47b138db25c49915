// The scale benchmark's cohort (bench/cohort_scale/run.py; docs/cohort.md "Cohorts of thousands"):
// element tables of N synthetic normals and a few patients made directly, without meshing. Per
// subject and element (centre c): t1w = g (1 + 0.1 f(c) + 0.03 n), pet = g (1 + 0.06 f'(c) +
// 0.5 (t1w / g - 1) + 0.04 n'), with f, f' seeded smooth fields (four plane waves of 1.5 to 3
// wavelengths across the ball), n, n' unit normal noise per element and g a global factor in
// [0.8, 1.2] (what proportional scaling removes). A patient's pet loses 25 % in a ball of radius
// 0.15 at a seeded place. Tables that exist are kept, so the cohorts of 50, 300 and 1,000 normals
// share their first tables.
//
//   vpm_bench_cohort_scale --out DIR --normals N [--patients P] [--level L] [--seed S]
//   vpm_bench_cohort_scale --read TABLE.h5     (its read time, median of 5, as JSON)
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <malloc.h>
#include <map>

#include "core/parallel.hpp"
#include "vpm/elements.hpp"
#include "vpm/sampling.hpp"

namespace {

using vpm::CanonicalElements;
using vpm::ElementTable;

struct Wave {
  Eigen::Vector3d k;
  double phase, amplitude;
};

// A smooth field in the ball: four plane waves.
std::vector<Wave> field(std::mt19937& rng) {
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Wave> w(4);
  for (Wave& x : w) {
    Eigen::Vector3d d(g(rng), g(rng), g(rng));
    x.k = d.normalized() * (2 * M_PI * (1.5 + 1.5 * u(rng)) / 2.0);
    x.phase = 2 * M_PI * u(rng);
    x.amplitude = 0.5 + 0.5 * u(rng);
  }
  return w;
}

double at(const std::vector<Wave>& w, const Eigen::Vector3d& c) {
  double v = 0;
  for (const Wave& x : w) v += x.amplitude * std::sin(x.k.dot(c) + x.phase);
  return v / 2;
}

ElementTable subject(const CanonicalElements& el, const std::vector<Eigen::Vector3d>& centres, const std::string& id,
                     unsigned seed, bool patient) {
  std::mt19937 rng(seed);
  const std::vector<Wave> f1 = field(rng), f2 = field(rng);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, 1);
  const double global = 0.8 + 0.4 * u(rng);
  const Eigen::Vector3d focus = Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 0.8;
  ElementTable t;
  t.definition = el.definition();
  t.subject = id;
  t.mesh = "synthetic";
  vpm::ElementFeature pet, t1w;
  pet.name = "pet";
  t1w.name = "t1w";
  pet.source = t1w.source = "synthetic";
  const int S = el.definition().samples;
  for (int e = 0; e < el.size(); ++e) {
    const Eigen::Vector3d& c = centres[static_cast<size_t>(e)];
    const double s = 1 + 0.1 * at(f1, c) + 0.03 * g(rng);
    double p = 1 + 0.06 * at(f2, c) + 0.5 * (s - 1) + 0.04 * g(rng);
    if (patient && (c - focus).norm() < 0.15) p *= 0.75;
    t1w.mean.push_back(global * s);
    pet.mean.push_back(global * p);
    t1w.std.push_back(0.02 * std::abs(g(rng)));
    pet.std.push_back(0.02 * std::abs(g(rng)));
    t1w.count.push_back(S);
    pet.count.push_back(S);
  }
  t.features = {pet, t1w};
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  // the vpm program's memory policy (apps/main.cpp): large arrays stay in one heap
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_ARENA_MAX, 1);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  std::map<std::string, std::string> a;
  for (int i = 1; i + 1 < argc; i += 2) a[argv[i]] = argv[i + 1];
  const auto number = [&](const char* key, int fallback) { return a.count(key) ? std::stoi(a[key]) : fallback; };
  if (a.count("--read")) {  // a table's read time: {"read_median_s", "elements"} (median of 5)
    std::vector<double> t;
    int n = 0;
    for (int i = 0; i < 5; ++i) {
      const auto start = std::chrono::steady_clock::now();
      n = vpm::read_subject_table(a["--read"]).definition.elements();
      t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(t.begin(), t.end());
    std::printf("{\"read_median_s\": %.3f, \"elements\": %d}\n", t[2], n);
    return 0;
  }
  const std::string out = a.count("--out") ? a["--out"] : "";
  if (out.empty() || argc % 2 == 0) {
    std::fprintf(stderr, "usage: vpm_bench_cohort_scale --out DIR --normals N [--patients P] [--level L] [--seed S]\n");
    return 2;
  }
  const int normals = number("--normals", 50), patients = number("--patients", 1);
  const unsigned seed = static_cast<unsigned>(number("--seed", 1));
  vpm::ElementDefinition d;
  d.layout = vpm::ElementLayout::graded;
  d.level = number("--level", 6);
  d.shells = vpm::graded_shells(d.level);
  d.samples = 8;
  const CanonicalElements el(d);
  std::vector<Eigen::Vector3d> centres(static_cast<size_t>(el.size()));
  for (int e = 0; e < el.size(); ++e) centres[static_cast<size_t>(e)] = el.centre(e);
  std::filesystem::create_directories(out);
  std::vector<std::pair<std::string, bool>> todo;
  for (int i = 0; i < normals; ++i) todo.emplace_back("sub-N" + std::to_string(10000 + i).substr(1), false);
  for (int i = 0; i < patients; ++i) todo.emplace_back("sub-P" + std::to_string(1000 + i).substr(1), true);
  const auto start = std::chrono::steady_clock::now();
  std::atomic<int> written{0};
  vpm::detail::parallel_for(static_cast<int>(todo.size()), 2, [&](int b, int e) {
    for (int i = b; i < e; ++i) {
      const auto& [id, patient] = todo[static_cast<size_t>(i)];
      const std::string path = out + "/" + id + "_pet.h5";
      if (std::filesystem::exists(path)) continue;
      vpm::write_subject_table(path, subject(el, centres, id, seed * 100003u + static_cast<unsigned>(i), patient));
      ++written;
    }
  });
  std::printf("cohort_scale: %zu tables in %s (%d written, %.1f s), %d elements each\n", todo.size(), out.c_str(), written.load(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), el.size());
  return 0;
}
