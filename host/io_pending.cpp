// Temporary: formats not written yet.
#include "io_formats.hpp"
#include "vpm/error.hpp"
namespace vpm::detail {
[[noreturn]] static void nyi(const std::string& p) { throw InputError(p + ": this format is not implemented yet"); }
TetMesh read_medit(const std::string& p) { nyi(p); }
void write_medit(const std::string& p, const TetMesh&) { nyi(p); }
TetMesh read_gmsh(const std::string& p) { nyi(p); }
void write_gmsh(const std::string& p, const TetMesh&) { nyi(p); }
TriSurface read_off(const std::string& p) { nyi(p); }
void write_off(const std::string& p, const TriSurface&) { nyi(p); }
TriSurface read_obj(const std::string& p) { nyi(p); }
void write_obj(const std::string& p, const TriSurface&) { nyi(p); }
TriSurface read_stl(const std::string& p) { nyi(p); }
void write_stl(const std::string& p, const TriSurface&, bool) { nyi(p); }
}
