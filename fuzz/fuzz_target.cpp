#include "fuzz_target.hpp"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <typeinfo>

#include "vpm/error.hpp"

namespace vpm::fuzz {

namespace fs = std::filesystem;

namespace {

void remove_scratch() {
  std::error_code ec;
  fs::remove_all(scratch_dir(), ec);
}

std::string make_scratch() {
  const char* tmp = std::getenv("TMPDIR");
  std::string templ = std::string(tmp && *tmp ? tmp : "/tmp") + "/vpm-fuzz-XXXXXX";
  if (!::mkdtemp(templ.data())) {
    std::perror("vpm fuzz: mkdtemp");
    std::abort();
  }
  std::atexit(remove_scratch);
  return templ;
}

}  // namespace

const std::string& scratch_dir() {
  // never destroyed: remove_scratch runs at exit, after static destructors registered later
  static const std::string* dir = new std::string(make_scratch());
  return *dir;
}

std::string write_scratch(const std::string& name, std::string_view bytes) {
  const fs::path path = fs::path(scratch_dir()) / name;
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out.flush()) {
    std::fprintf(stderr, "vpm fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path.string();
}

std::pair<std::string_view, std::string_view> split_files(std::string_view bytes) {
  const size_t at = bytes.find(kSplit);
  if (at == std::string_view::npos) return {bytes, {}};
  return {bytes.substr(0, at), bytes.substr(at + kSplit.size())};
}

void expect_input_error_only(const std::function<void()>& read) {
  try {
    read();
  } catch (const InputError& e) {
    // the documented refusal; VPM_FUZZ_VERBOSE=1 prints it (to see what the seeds reach)
    static const bool verbose = std::getenv("VPM_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "InputError: %s\n", e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vpm fuzz: a reader threw %s (not vpm::InputError): %s\n", typeid(e).name(), e.what());
    std::abort();
  } catch (...) {
    std::fprintf(stderr, "vpm fuzz: a reader threw something that is not a std::exception\n");
    std::abort();
  }
}

void require(bool ok, const char* promise) {
  if (ok) return;
  std::fprintf(stderr, "vpm fuzz: a reader broke its promise: %s\n", promise);
  std::abort();
}

void require_well_formed(const TetMesh& mesh) {
  const Eigen::Index n = mesh.vertices.rows();
  for (Eigen::Index i = 0; i < mesh.tets.size(); ++i)
    require(mesh.tets.data()[i] >= 0 && mesh.tets.data()[i] < n, "tet vertex indices in 0..n-1");
  for (const Field& f : mesh.point_data) require(f.values.rows() == n, "a point field has one row per vertex");
  for (const Field& f : mesh.cell_data) require(f.values.rows() == mesh.tets.rows(), "a cell field has one row per tet");
}

void require_well_formed(const TriSurface& surface) {
  const Eigen::Index n = surface.vertices.rows();
  for (Eigen::Index i = 0; i < surface.triangles.size(); ++i)
    require(surface.triangles.data()[i] >= 0 && surface.triangles.data()[i] < n, "triangle vertex indices in 0..n-1");
}

}  // namespace vpm::fuzz
