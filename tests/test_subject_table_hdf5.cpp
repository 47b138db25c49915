// Subject tables in HDF5 (vpm/sampling.hpp, TableFormat::hdf5): the round trip at float32
// precision, partial reads, the same table as the TSV export, `vpm convert` both ways, h5py
// reading it without vpm, and files that are not tables (truncated, corrupt, counts beyond the
// definition, another format) refused with the file and the place named.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include "io/hdf5.hpp"
#include "support/elements.hpp"
#include "support/process.hpp"
#include "support/scratch.hpp"
#include "vpm/error.hpp"
#include "vpm/sampling.hpp"

using namespace vpm;

namespace {

ElementTable table(const CanonicalElements& el) {
  ElementTable t;
  t.definition = el.definition();
  t.subject = "sub-01";
  t.mesh = "sub-01_registered.vtu";
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0, 1);
  for (const char* name : {"pet", "t1w"}) {
    ElementFeature f;
    f.name = name;
    f.source = std::string("/data/sub-01_") + name + ".nii.gz";
    for (int e = 0; e < el.size(); ++e) {
      f.mean.push_back(1000 + 100 * g(rng));
      f.std.push_back(std::abs(10 * g(rng)));
      f.count.push_back(e % 5 == 0 ? 3 : el.definition().samples);
    }
    t.features.push_back(f);
  }
  ElementLabels l;
  l.source = "/data/sub-01_dseg.nii.gz";
  l.labels = {3, 17, 42};
  for (size_t k = 0; k < 3; ++k) {
    l.fraction.emplace_back();
    for (int e = 0; e < el.size(); ++e) l.fraction.back().push_back(((e + static_cast<int>(k)) % 9) / 8.0);
  }
  t.label_images.push_back(l);
  return t;
}

void same_as_float(const std::vector<double>& got, const std::vector<double>& want) {
  REQUIRE(got.size() == want.size());
  for (size_t i = 0; i < got.size(); ++i) REQUIRE(got[i] == double(static_cast<float>(want[i])));
}

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

TEST_CASE("subject table hdf5: round trip at float32, partial reads, the TSV export, vpm convert") {
  const CanonicalElements el(test::small_elements());
  const ElementTable t = table(el);
  const std::string dir = test::fresh_dir("table_hdf5");
  write_subject_table(dir + "/t.h5", t);
  const ElementTable r = read_subject_table(dir + "/t.h5");
  CHECK(r.definition == t.definition);
  CHECK(r.subject == "sub-01");
  CHECK(r.mesh == t.mesh);
  REQUIRE(r.features.size() == 2);
  for (size_t f = 0; f < 2; ++f) {
    CHECK(r.features[f].name == t.features[f].name);
    CHECK(r.features[f].source == t.features[f].source);
    same_as_float(r.features[f].mean, t.features[f].mean);
    // the spread to 12 significant bits: within 1/4096 relative, the 12 low mantissa bits clear
    for (size_t e = 0; e < t.features[f].std.size(); ++e) {
      REQUIRE(std::abs(r.features[f].std[e] - t.features[f].std[e]) <= std::abs(t.features[f].std[e]) / 4096 + 1e-300);
      const float v = static_cast<float>(r.features[f].std[e]);
      std::uint32_t bits;
      std::memcpy(&bits, &v, sizeof bits);
      REQUIRE((bits & 0xfffu) == 0);
    }
    CHECK(r.features[f].count == t.features[f].count);
  }
  REQUIRE(r.label_images.size() == 1);
  CHECK(r.label_images[0].labels == t.label_images[0].labels);
  CHECK(r.label_images[0].source == t.label_images[0].source);
  for (size_t k = 0; k < 3; ++k) same_as_float(r.label_images[0].fraction[k], t.label_images[0].fraction[k]);

  TableColumns only;
  only.features = {"t1w", "absent"};
  only.spread = only.labels = false;
  const ElementTable p = read_subject_table(dir + "/t.h5", only);
  REQUIRE(p.features.size() == 1);
  CHECK(p.features[0].name == "t1w");
  CHECK(p.features[0].std.empty());
  CHECK(p.features[0].mean == r.features[1].mean);
  CHECK(p.label_images.empty());

  // the TSV export holds the same table (ten digits of the float32 values), and converts back
  REQUIRE(test::run_status(std::string(VPM_BINARY) + " convert " + dir + "/t.h5 " + dir + "/t.tsv --quiet") == 0);
  const ElementTable x = read_subject_table(dir + "/t.tsv");
  for (size_t f = 0; f < 2; ++f)
    for (size_t e = 0; e < x.features[f].mean.size(); ++e)
      REQUIRE(x.features[f].mean[e] == Approx(r.features[f].mean[e]).epsilon(1e-9));
  REQUIRE(test::run_status(std::string(VPM_BINARY) + " convert " + dir + "/t.tsv " + dir + "/back.h5 --quiet") == 0);
  CHECK(read_subject_table(dir + "/back.h5").features[0].mean == r.features[0].mean);
  CHECK(table_format(dir + "/a.hdf5") == TableFormat::hdf5);
  CHECK_THROWS_WITH(table_format(dir + "/a.csv"), Catch::Contains("a.csv: a subject table is .h5"));
}

TEST_CASE("subject table hdf5: h5py reads the table without vpm") {
  const CanonicalElements el(test::small_elements());
  const ElementTable t = table(el);
  const std::string dir = test::fresh_dir("table_h5py");
  write_subject_table(dir + "/t.h5", t);
  const std::string script = dir + "/read.py";
  std::ofstream(script) << "import json, sys, h5py\n"
                           "f = h5py.File(sys.argv[1], 'r')\n"
                           "m = json.loads(f.attrs['metadata'])\n"
                           "assert f.attrs['format'] == 'vpm element table', f.attrs['format']\n"
                           "assert f.attrs['subject'] == 'sub-01'\n"
                           "pet = f['features/pet/mean'][()]\n"
                           "assert pet.dtype.name == 'float32' and pet.shape == (m['elements'],)\n"
                           "print(repr(float(pet[5])), int(f['features/pet/count'][0]), f['labels/0/fraction'].shape)\n";
  const std::string out = dir + "/out.txt";
  REQUIRE(test::run_status("/usr/bin/python3 " + script + " " + dir + "/t.h5 > " + out) == 0);
  const std::string printed = test::slurp(out);
  CHECK(std::stod(printed) == double(static_cast<float>(t.features[0].mean[5])));
  CHECK_THAT(printed, Catch::Contains(" 3 (3, " + std::to_string(el.size()) + ")"));
}

TEST_CASE("subject table hdf5: truncated, corrupt and foreign files are refused naming the file and the place") {
  const CanonicalElements el(test::small_elements());
  const std::string dir = test::fresh_dir("table_hdf5_bad");
  write_subject_table(dir + "/t.h5", table(el));
  const std::string good = bytes_of(dir + "/t.h5");
  std::ofstream(dir + "/cut.h5", std::ios::binary) << good.substr(0, good.size() * 2 / 3);
  CHECK_THROWS_WITH(read_subject_table(dir + "/cut.h5"), Catch::Contains("cut.h5"));
  // every 97th byte flipped in turn: an InputError or the same table, never a crash
  int refused = 0;
  for (size_t at = 0; at < good.size(); at += 97) {
    std::string bad = good;
    bad[at] = static_cast<char>(bad[at] ^ 0x5a);
    std::ofstream(dir + "/flip.h5", std::ios::binary) << bad;
    try {
      read_subject_table(dir + "/flip.h5");
    } catch (const InputError& e) {
      ++refused;
      REQUIRE_THAT(e.what(), Catch::Contains("flip.h5"));
    }
  }
  CHECK(refused > 0);
  // a count beyond the definition's samples, named with its dataset and element
  {
    ElementTable t = table(el);
    t.label_images.clear();
    t.features.resize(1);
    t.features[0].count[4] = 99;
    write_subject_table(dir + "/count.h5", t);
  }
  CHECK_THROWS_WITH(read_subject_table(dir + "/count.h5"), Catch::Contains("/features/pet/count: element 4 has 99 samples"));
  // an HDF5 file that is not a table
  {
    detail::h5::Writer w(dir + "/other.h5");
    w.attribute("/", "format", std::string("something else"));
    w.commit();
  }
  CHECK_THROWS_WITH(read_subject_table(dir + "/other.h5"), Catch::Contains("other.h5: not a vpm element table"));
  std::ofstream(dir + "/text.h5") << "element\tshell\ttriangle\tsamples\n";
  CHECK_THROWS_WITH(read_subject_table(dir + "/text.h5"), Catch::Contains("text.h5: not an HDF5 file"));
}
