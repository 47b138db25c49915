// Faults mid-run (docs/robustness.md, "Faults mid-run"): SIGKILL while each kind of output is
// written, a write that fails, an OpenCL program that does not build, a device buffer larger
// than the device allows, a solver that cannot converge. Each ends with a clear message and exit
// status, and no partial or temporary file is left anywhere.
#include <signal.h>
#include <sys/resource.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <set>

#include "core/atomic_file.hpp"
#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "support/shapes.hpp"
#include "support/kill.hpp"
#include "support/process.hpp"
#include "support/scratch.hpp"
#include "core/device_cl.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/cohort_view.hpp"
#include "vpm/config.hpp"
#include "vpm/device.hpp"
#include "vpm/elements.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/landmarks.hpp"
#include "vpm/statistics.hpp"
#include "vpm/topology.hpp"
#include "vpm/view_page.hpp"
#include "vpm/validate.hpp"

using namespace vpm;
namespace fs = std::filesystem;

namespace {

std::string fresh_dir(const std::string& name) { return test::fresh_dir("faults_" + name); }

// One kind of output: its file names in the folder, how to write them, how to check one.
struct Output {
  std::string kind;
  std::vector<std::string> files;                        // what may exist in the folder
  std::function<void(const std::string& dir)> write;     // writes every file once
  std::function<bool(const std::string& path)> valid;    // a complete file
};

// The output name `e` is a hidden temporary of (".NAME.tmp.*"), or "" if none.
std::string temporary_of(const Output& o, const std::string& e) {
  for (const auto& f : o.files)
    if (e.rfind("." + f + ".tmp.", 0) == 0) return f;
  return "";
}

// Writes `o` in a loop in a child process killed after a random delay, `trials` times (every
// other trial over the files left by the one before: the replacing path). After each kill the
// folder holds the output's own names, each complete, and at most, for a file being replaced, a
// complete hidden ".NAME.tmp.*" copy: the microseconds between linking the finished file under
// that name and renaming it over the old one (docs/robustness.md). With `named` (the fallback)
// a kill may leave a partial hidden temporary, never a partial file under the final name.
void kill_while_writing(const Output& o, int trials, double max_delay_s, unsigned seed, bool named = false) {
  const std::string dir = fresh_dir("kill_" + o.kind + (named ? "_named" : ""));
  const std::string check = fresh_dir("kill_" + o.kind + "_check");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> delay(0.0, max_delay_s);
  int present = 0, windows = 0;
  // on a loaded machine the child's first write can outlast every random delay: then further
  // kills, each later than the one before, until one lands after a write (or 12 more)
  double late = max_delay_s;
  for (int t = 0; t < trials || (present == 0 && t < trials + 12); ++t) {
    if (t % 2 == 0)
      for (const auto& f : o.files) fs::remove(dir + "/" + f);
    const pid_t pid = test::fork_child([&] {
      if (named) detail::atomic_file_force_named_fallback(true);
      for (;;) o.write(dir);
    });
    REQUIRE(test::kill_after(pid, t < trials ? delay(rng) : (late *= 1.5)));
    for (const auto& e : test::folder_entries(dir)) {
      INFO(o.kind << " trial " << t << ": " << e);
      const std::string of = temporary_of(o, e);
      if (!of.empty()) {  // a hidden temporary: partial only in the named fallback
        if (!named) {
          REQUIRE(fs::exists(dir + "/" + of));  // only while replacing a file
          fs::copy_file(dir + "/" + e, check + "/" + of, fs::copy_options::overwrite_existing);
          CHECK(o.valid(check + "/" + of));
          ++windows;
        }
        fs::remove(dir + "/" + e);
        continue;
      }
      REQUIRE(std::find(o.files.begin(), o.files.end(), e) != o.files.end());
      CHECK(o.valid(dir + "/" + e));
      ++present;
    }
  }
  INFO(o.kind << ": output present after " << present << " of " << trials << " kills (and the later ones)");
  CHECK(present > 0);  // the kills did not all land before the first write finished
  if (windows) WARN(o.kind << ": " << windows << " kills fell between the link and the rename (a whole hidden copy left)");
}

template <class F>
bool no_throw(F f) {
  try {
    f();
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

std::vector<Output> outputs() {
  static const TetMesh mesh = test::cube_mesh(24);  // 82,944 tets, 15,625 vertices
  static const TriSurface surf = [] {
    TriSurface s;
    s.vertices = mesh.vertices;
    s.triangles = boundary_faces(mesh.tets);
    return s;
  }();
  auto mesh_output = [](const std::string& kind, const std::string& name, VtuEncoding enc) {
    return Output{kind, {name}, [=](const std::string& d) { write_mesh(d + "/" + name, mesh, enc); },
                  [](const std::string& p) {
                    return no_throw([&] { REQUIRE(read_mesh(p).num_tets() == mesh.num_tets()); });
                  }};
  };
  std::vector<Output> out = {
      mesh_output("vtu_binary", "m.vtu", VtuEncoding::binary),
      mesh_output("vtu_ascii", "m.vtu", VtuEncoding::ascii),
      mesh_output("msh", "m.msh", VtuEncoding::binary),
      mesh_output("medit", "m.mesh", VtuEncoding::binary),
  };
  out.push_back({"surface_off", {"s.off"}, [](const std::string& d) { write_surface(d + "/s.off", surf); },
                 [](const std::string& p) {
                   return no_throw([&] { REQUIRE(read_surface(p).triangles.rows() == surf.triangles.rows()); });
                 }});
  out.push_back({"json", {"r.json"},
                 [](const std::string& d) {
                   Json j = Json::array();
                   for (int i = 0; i < 200000; ++i) j.push_back(Json(i * 0.5));
                   write_json_file(d + "/r.json", j);
                 },
                 [](const std::string& p) {
                   return no_throw([&] { REQUIRE(read_json_file(p).size() == 200000); });
                 }});
  static const Points inside = 0.5 * mesh.vertices;  // landmarks are ball coordinates
  out.push_back({"landmarks_csv", {"l.csv"}, [](const std::string& d) { write_landmarks_csv(d + "/l.csv", inside); },
                 [](const std::string& p) {
                   return no_throw([&] { REQUIRE(read_landmarks_csv(p, inside).points.rows() == inside.rows()); });
                 }});
  static const CanonicalElements elements = [] {
    ElementDefinition def;
    def.level = 5, def.shells = 8, def.samples = 1;  // 163,840 rows
    return CanonicalElements(def);
  }();
  out.push_back({"tsv_sidecar", {"e.tsv", "e.json"},
                 [](const std::string& d) { write_element_table(d + "/e.tsv", elements); },
                 [](const std::string& p) {
                   if (p.size() > 5 && p.substr(p.size() - 5) == ".json") return no_throw([&] { read_json_file(p); });
                   const std::string text = test::slurp(p);
                   return !text.empty() && text.back() == '\n' &&
                          std::count(text.begin(), text.end(), '\n') == elements.size() + 1;
                 }});
  if (view_page_available()) {  // the cohort's web page (vpm view): one HTML file with its arrays inline
    static const CohortView view = [] {
      const CanonicalElements el(ElementDefinition{4, 8, 1});
      CohortView v;
      v.definition = el.definition();
      v.mid_radii = shell_mid_radii(el);
      v.display = icosphere(4);
      v.display_triangle_element = display_triangle_elements(el, v.display);
      v.features.push_back({"pet", Normalisation::proportional, 0, 0, {}, "", {}, 3, std::vector<float>(el.size(), 1.0f),
                            std::vector<float>(el.size(), 0.1f)});
      ViewSubject sub;
      sub.id = "sub-P01";
      sub.patient = true;
      sub.native = std::vector<float>(size_t(el.definition().shells) * v.display.vertices.rows() * 3, 1.0f);
      sub.values["pet"] = std::vector<float>(el.size(), 1.0f);
      sub.z["pet"] = std::vector<float>(el.size(), 0.5f);
      v.subjects.push_back(sub);
      return v;
    }();
    out.push_back({"html", {"v.html"}, [](const std::string& d) { write_view_page(d + "/v.html", view); },
                   [](const std::string& p) {
                     const std::string page = test::slurp(p);
                     return page.size() > 1000 && page.find("</html>") != std::string::npos &&
                            page.find_first_not_of(" \n", page.rfind("</html>") + 7) == std::string::npos;
                   }});
  }
  if (VPM_HAVE_NIFTI) {
    static const Image img = [] {
      Image im;
      im.dims = {96, 96, 96};
      im.data.resize(96 * 96 * 96);
      for (size_t i = 0; i < im.data.size(); ++i) im.data[i] = float(i % 977);
      return im;
    }();
    for (const std::string name : {"i.nii.gz", "i.nii"})
      out.push_back({"nifti_" + name.substr(2), {name}, [=](const std::string& d) { write_nifti(d + "/" + name, img); },
                     [](const std::string& p) {
                       return no_throw([&] { REQUIRE(read_nifti(p).data == img.data); });
                     }});
  }
  return out;
}

}  // namespace

TEST_CASE("faults: SIGKILL while each kind of output is written leaves it absent or whole, and no other file") {
  unsigned seed = 1;
  for (const Output& o : outputs()) {
    // a first write alone, timed, so the kills fall over a few writes
    const std::string dir = fresh_dir("time_" + o.kind);
    const double t0 = test::now_s();
    o.write(dir);
    const double once = test::now_s() - t0;
    INFO(o.kind << ": one write takes " << once << " s");
    kill_while_writing(o, 10, 3 * once + 0.1, seed++);
  }
}

TEST_CASE("faults: without O_TMPFILE the named temporary never shows a partial file under the final name") {
  // the fallback path (NFS, Lustre): a SIGKILL may leave a hidden ".NAME.tmp.PID.K", never a
  // partial NAME; an exception before commit() removes the temporary
  const Output o = outputs().front();
  kill_while_writing(o, 6, 0.5, 99, true);
  const std::string dir = fresh_dir("named_throw");
  detail::atomic_file_force_named_fallback(true);
  try {
    detail::AtomicFile f(dir + "/x.txt");
    CHECK_FALSE(f.unnamed());
    f.stream() << "partial";
    CHECK(test::folder_entries(dir).size() == 1);  // the hidden temporary
    throw std::runtime_error("stage failed");
  } catch (const std::runtime_error&) {
  }
  CHECK(test::folder_entries(dir).empty());
  {
    detail::AtomicFile f(dir + "/x.txt");
    f.stream() << "whole";
    f.commit();
  }
  detail::atomic_file_force_named_fallback(false);
  CHECK(test::folder_entries(dir) == std::vector<std::string>{"x.txt"});
  CHECK(test::slurp(dir + "/x.txt") == "whole");
}

TEST_CASE("faults: outputs are unnamed until committed on this file system (O_TMPFILE)") {
  const std::string dir = fresh_dir("unnamed");
  detail::AtomicFile f(dir + "/x.txt");
  if (!f.unnamed()) {
    WARN("no O_TMPFILE under " << dir << ": the named fallback is in use here");
    return;
  }
  f.stream() << "data";
  f.stream().flush();
  CHECK(test::folder_entries(dir).empty());  // nothing in the folder until commit()
  f.commit();
  CHECK(test::folder_entries(dir) == std::vector<std::string>{"x.txt"});
  {  // replacing: the old contents stay until the new file is complete
    detail::AtomicFile g(dir + "/x.txt");
    g.stream() << "new data";
    g.stream().flush();
    CHECK(test::slurp(dir + "/x.txt") == "data");
    g.commit();
  }
  CHECK(test::slurp(dir + "/x.txt") == "new data");
  CHECK(test::folder_entries(dir) == std::vector<std::string>{"x.txt"});
}

TEST_CASE("faults: a write that fails (file size limit) names the file and the reason, and leaves nothing") {
  const std::string dir = fresh_dir("fsize");
  const TetMesh mesh = test::cube_mesh(16);
  const pid_t pid = test::fork_child([&] {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit lim{1 << 16, 1 << 16};
    ::setrlimit(RLIMIT_FSIZE, &lim);
    try {
      write_mesh(dir + "/m.vtu", mesh, VtuEncoding::ascii);
    } catch (const InputError& e) {
      const std::string m = e.what();
      if (m.find(dir + "/m.vtu") != std::string::npos && m.find("write failed: File too large") != std::string::npos)
        ::_exit(0);
      ::_exit(2);
    }
    ::_exit(3);
  });
  CHECK(test::wait_status(pid) == 0);
  CHECK(test::folder_entries(dir).empty());
  // the program: a ulimit -f makes write(2) fail (vpm ignores SIGXFSZ, which would kill it): exit 2
  const std::string in = dir + "/in.vtu", err = dir + "/err.txt";
  write_mesh(in, mesh);
  const int rc = test::run_status("ulimit -f 128; " + std::string(VPM_BINARY) + " convert " + in + " " + dir +
                                  "/out.vtu --ascii 2> " + err);
  CHECK(rc == kExitInput);
  CHECK(test::slurp(err).find("out.vtu: write failed: File too large") != std::string::npos);
  CHECK(test::folder_entries(dir) == std::vector<std::string>{"err.txt", "in.vtu"});
}

TEST_CASE("faults: an OpenCL program that does not build is a DeviceError naming it and its first log lines") {
  auto dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device: skipped");
    return;
  }
  const std::string source = "__kernel void broken(__global real* x) { x[0] = no_such_name_here; }\n";
  try {
    dev->cl().build_program("kernels/broken.cl", source);
    FAIL("the broken program built");
  } catch (const DeviceError& e) {
    const std::string m = e.what();
    INFO(m);
    CHECK(m.find("kernels/broken.cl: OpenCL build failed on " + dev->name()) == 0);
    CHECK(m.find("no_such_name_here") != std::string::npos);  // the compiler's own words
    CHECK(m.find('\n') == std::string::npos);                 // one line
  }
  // the embedded programs still build: the failure is not cached as a success or a poison
  CHECK_NOTHROW(dev->cl().kernel("solver", "spmv"));
}

TEST_CASE("kernel headers: a shared .clh is expanded from the embedded sources, an unknown one is named") {
  auto dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device: skipped");
    return;
  }
  // kernels/tet_locate.clh compiles on the device as it does on the host
  const std::string uses = "#include \"tet_locate.clh\"\n"
                           "__kernel void b(__global const real* inv, __global real* l) {\n"
                           "  real q[4];\n  tl_bary(inv, 0, 0.25, 0.25, 0.25, q);\n  l[0] = tl_min4(q);\n}\n";
  CHECK_NOTHROW(dev->cl().build_program("kernels/uses.cl", uses));
  try {
    dev->cl().build_program("kernels/missing.cl", "// a header\n#include \"no_such.clh\"\n");
    FAIL("a program with an unknown header built");
  } catch (const DeviceError& e) {
    CHECK(std::string(e.what()) == "kernels/missing.cl:2: no embedded kernel header 'no_such.clh'");
  }
}

TEST_CASE("faults: vpm map exits 5 naming the program when the driver cannot build a kernel") {
  auto dev = test::opencl_device();
  if (!dev || dev->description().platform.find("Portable Computing Language") == std::string::npos) {
    WARN("needs PoCL (POCL_EXTRA_BUILD_FLAGS injects the build failure): skipped");
    return;
  }
  const std::string dir = fresh_dir("build_fails"), in = dir + "/in.vtu", err = dir + "/err.txt";
  write_mesh(in, test::ellipsoid_mesh(4));
  const std::string spec = std::to_string(dev->description().platform_index) + ":" +
                           std::to_string(dev->description().device_index);
  // PoCL appends these options to every build: a macro redefined under -Werror is a compile error
  const pid_t pid = test::spawn({VPM_BINARY, "map", in, "-o", dir + "/out.vtu", "--report", dir + "/r.json"}, err,
                                {"VPM_DEVICE=" + spec, "POCL_EXTRA_BUILD_FLAGS=-Werror -DVPM_FAULT -DVPM_FAULT=2"});
  CHECK(test::wait_status(pid) == kExitDevice);
  const std::string all = test::slurp(err);
  const std::string m = all.substr(all.find("vpm map: "));  // PoCL itself prints "1 error generated." first
  INFO(all);
  CHECK(m.find("vpm map: device error: kernels/") == 0);
  CHECK(m.find(".cl: OpenCL build failed on " + dev->name()) != std::string::npos);
  CHECK(m.find("'VPM_FAULT' macro redefined") != std::string::npos);  // the compiler's log
  CHECK(std::count(m.begin(), m.end(), '\n') == 1);                   // vpm's message: one line
  CHECK(test::folder_entries(dir) == std::vector<std::string>{"err.txt", "in.vtu"});
}

TEST_CASE("faults: a device buffer larger than CL_DEVICE_MAX_MEM_ALLOC_SIZE is a DeviceError, not a crash") {
  auto dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device: skipped");
    return;
  }
  const unsigned long long max_alloc = dev->description().max_alloc_bytes;
  REQUIRE(max_alloc > 0);
  try {
    dev->check_buffer(max_alloc + 1, "Laplacian of 1 tets");
    FAIL("no DeviceError");
  } catch (const DeviceError& e) {
    const std::string m = e.what();
    CHECK(m.find("Laplacian of 1 tets: a buffer of " + std::to_string(max_alloc + 1) + " bytes") == 0);
    CHECK(m.find("CL_DEVICE_MAX_MEM_ALLOC_SIZE = " + std::to_string(max_alloc)) != std::string::npos);
  }
  CHECK_NOTHROW(dev->check_buffer(max_alloc, "at the limit"));
  CHECK_NOTHROW(Device::host()->check_buffer(~0ULL, "the host has no device limit"));
}

TEST_CASE("faults: a solver that cannot converge ends the map with what it reached, on every device") {
  TetMesh m = test::ellipsoid_mesh(4);
  const ValidationReport vr = validate_mesh(m, "capped.vtu");
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    BallMapOptions o;
    o.volume.solver_tolerance = 1e-300;  // unreachable: the Moser round's Poisson solve stops at its cap
    try {
      map_to_ball(*dev, m, vr, "capped.vtu", o);
      FAIL("the map converged");
    } catch (const NumericalError& e) {
      const std::string msg = e.what();
      INFO(msg);
      CHECK(msg.find("capped.vtu: ") == 0);
      CHECK(msg.find("relative residual") != std::string::npos);
      CHECK(msg.find("iterations") != std::string::npos);
      CHECK(msg.find("nothing written") != std::string::npos);
    }
  }
}

namespace {

// A command run whole once (its outputs kept as the reference), then killed at random moments:
// after each kill its outputs are absent or complete (a .vtu byte-identical to the whole run's,
// a JSON report that parses) and nothing else is in the folder.
void kill_command(const std::string& name, const std::vector<std::string>& args, const std::vector<std::string>& outs,
                  const std::string& input, int trials, unsigned seed) {
  const std::string dir = fresh_dir("cmd_" + name), ref = fresh_dir("cmd_" + name + "_ref");
  fs::copy_file(input, dir + "/in.vtu");
  auto argv = [&](const std::string& d) {
    std::vector<std::string> a{VPM_BINARY};
    for (const auto& s : args) a.push_back(s == "IN" ? dir + "/in.vtu" : s.rfind("OUT/", 0) == 0 ? d + s.substr(3) : s);
    return a;
  };
  const double t0 = test::now_s();
  REQUIRE(test::wait_status(test::spawn(argv(ref))) == 0);
  const double whole = test::now_s() - t0;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> delay(0.0, 1.1 * whole);
  int killed = 0;
  for (int t = 0; t < trials; ++t) {
    if (t % 2 == 0)
      for (const auto& o : outs) fs::remove(dir + "/" + o);
    killed += test::kill_after(test::spawn(argv(dir)), delay(rng));
    for (const auto& e : test::folder_entries(dir)) {
      INFO(name << " trial " << t << " (whole run " << whole << " s): " << e);
      if (e == "in.vtu") continue;
      REQUIRE(std::find(outs.begin(), outs.end(), e) != outs.end());
      if (e.size() > 5 && e.substr(e.size() - 5) == ".json")
        CHECK(no_throw([&] { REQUIRE(read_json_file(dir + "/" + e).find("final")); }));
      else
        CHECK(test::slurp(dir + "/" + e) == test::slurp(ref + "/" + e));
    }
  }
  CHECK(killed > 0);
}

}  // namespace

TEST_CASE("faults: SIGKILL at random moments of vpm convert and vpm map leaves outputs absent or whole") {
  const std::string dir = fresh_dir("cmd_inputs");
  write_mesh(dir + "/big.vtu", test::cube_mesh(36));  // 279,936 tets
  kill_command("convert_vtu", {"convert", "IN", "OUT/c.vtu", "--ascii"}, {"c.vtu"}, dir + "/big.vtu", 12, 7);
  kill_command("convert_msh", {"convert", "IN", "OUT/c.msh"}, {"c.msh"}, dir + "/big.vtu", 8, 8);
  write_mesh(dir + "/ellipsoid.vtu", test::ellipsoid_mesh(10));  // 6,000 tets
  kill_command("map", {"map", "IN", "-o", "OUT/m.vtu", "--report", "OUT/m.json", "--quiet"}, {"m.vtu", "m.json"},
               dir + "/ellipsoid.vtu", 8, 9);
}
