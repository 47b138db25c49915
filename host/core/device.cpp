#include "core/device_cl.hpp"

#include <CL/cl.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <mutex>
#include <sstream>

#include "vpm/error.hpp"

namespace vpm {
namespace detail {
const std::map<std::string, std::string>& embedded_kernel_sources();
}

namespace bc = boost::compute;

const char* to_string(DeviceKind kind) {
  switch (kind) {
    case DeviceKind::host: return "host";
    case DeviceKind::cpu: return "cpu";
    case DeviceKind::gpu: return "gpu";
    case DeviceKind::accelerator: return "accelerator";
    case DeviceKind::other: break;
  }
  return "other";
}

std::string DeviceDescription::label() const {
  return std::to_string(platform_index) + ":" + std::to_string(device_index) + " " + platform +
         ": " + name;
}

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string trim(std::string s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  return s.substr(i);
}

std::string info_string(cl_device_id d, cl_device_info what) {
  size_t n = 0;
  if (clGetDeviceInfo(d, what, 0, nullptr, &n) != CL_SUCCESS) return {};
  std::string s(n, '\0');
  clGetDeviceInfo(d, what, n, s.data(), nullptr);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return trim(s);
}

struct RawDevice {
  DeviceDescription desc;
  cl_device_id id;
};

std::vector<RawDevice> enumerate(std::string* error) {
  std::vector<RawDevice> out;
  cl_uint np = 0;
  cl_int err = clGetPlatformIDs(0, nullptr, &np);
  if (err != CL_SUCCESS || np == 0) {
    if (error) *error = "no OpenCL platform (ICD) found (clGetPlatformIDs returned " +
                        std::to_string(err) + "); install pocl-opencl-icd or a GPU driver";
    return out;
  }
  std::vector<cl_platform_id> platforms(np);
  clGetPlatformIDs(np, platforms.data(), nullptr);
  for (cl_uint p = 0; p < np; ++p) {
    size_t n = 0;
    clGetPlatformInfo(platforms[p], CL_PLATFORM_NAME, 0, nullptr, &n);
    std::string pname(n, '\0');
    clGetPlatformInfo(platforms[p], CL_PLATFORM_NAME, n, pname.data(), nullptr);
    while (!pname.empty() && pname.back() == '\0') pname.pop_back();
    cl_uint nd = 0;
    if (clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, 0, nullptr, &nd) != CL_SUCCESS) continue;
    std::vector<cl_device_id> ids(nd);
    clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, nd, ids.data(), nullptr);
    for (cl_uint d = 0; d < nd; ++d) {
      RawDevice r;
      r.id = ids[d];
      r.desc.platform_index = static_cast<int>(p);
      r.desc.device_index = static_cast<int>(d);
      r.desc.platform = trim(pname);
      r.desc.name = info_string(ids[d], CL_DEVICE_NAME);
      cl_device_type t = 0;
      clGetDeviceInfo(ids[d], CL_DEVICE_TYPE, sizeof t, &t, nullptr);
      r.desc.kind = (t & CL_DEVICE_TYPE_GPU)           ? DeviceKind::gpu
                    : (t & CL_DEVICE_TYPE_CPU)         ? DeviceKind::cpu
                    : (t & CL_DEVICE_TYPE_ACCELERATOR) ? DeviceKind::accelerator
                                                       : DeviceKind::other;
      cl_device_fp_config fp = 0;
      clGetDeviceInfo(ids[d], CL_DEVICE_DOUBLE_FP_CONFIG, sizeof fp, &fp, nullptr);
      std::string ext = info_string(ids[d], CL_DEVICE_EXTENSIONS);
      r.desc.fp64 = fp != 0 || ext.find("cl_khr_fp64") != std::string::npos;
      cl_uint cu = 0;
      clGetDeviceInfo(ids[d], CL_DEVICE_MAX_COMPUTE_UNITS, sizeof cu, &cu, nullptr);
      r.desc.compute_units = cu;
      cl_ulong mem = 0;
      clGetDeviceInfo(ids[d], CL_DEVICE_GLOBAL_MEM_SIZE, sizeof mem, &mem, nullptr);
      r.desc.global_memory_bytes = mem;
      cl_ulong max_alloc = 0;
      clGetDeviceInfo(ids[d], CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof max_alloc, &max_alloc, nullptr);
      r.desc.max_alloc_bytes = max_alloc;
      out.push_back(r);
    }
  }
  if (out.empty() && error) *error = "OpenCL platforms exist but report no device";
  return out;
}

std::string device_list_text(const std::vector<RawDevice>& devs, const std::string& why) {
  std::string s = "available: host";
  for (const auto& d : devs) s += "; " + d.desc.label() + " (" + to_string(d.desc.kind) + ")";
  if (devs.empty() && !why.empty()) s += " (" + why + ")";
  return s;
}

}  // namespace

std::vector<DeviceDescription> list_opencl_devices(std::string* error) {
  std::vector<DeviceDescription> out;
  for (auto& r : enumerate(error)) out.push_back(r.desc);
  return out;
}

std::shared_ptr<Device> Device::host() {
  std::shared_ptr<Device> d(new Device());
  d->host_ = true;
  d->desc_.name = "host";
  d->desc_.kind = DeviceKind::host;
  d->desc_.fp64 = true;
  return d;
}

std::shared_ptr<Device> Device::select(const std::string& spec_in) {
  const std::string spec = lower(trim(spec_in));
  if (spec == "host") return host();
  std::string why;
  auto devs = enumerate(&why);
  const RawDevice* chosen = nullptr;
  if (spec.empty()) {
    for (auto& d : devs)
      if (d.desc.kind == DeviceKind::gpu && d.desc.fp64) { chosen = &d; break; }
    if (!chosen)
      for (auto& d : devs)
        if (d.desc.kind == DeviceKind::cpu && d.desc.fp64) { chosen = &d; break; }
    if (!chosen) return host();  // the documented default when no fp64 OpenCL device exists
  } else if (spec == "cpu" || spec == "gpu") {
    for (auto& d : devs)
      if (to_string(d.desc.kind) == spec) { chosen = &d; break; }
  } else if (spec.find(':') != std::string::npos &&
             std::all_of(spec.begin(), spec.end(),
                         [](char c) { return std::isdigit(static_cast<unsigned char>(c)) || c == ':'; })) {
    int p = -1, q = -1;
    char colon = 0;
    std::istringstream in(spec);
    in >> p >> colon >> q;
    for (auto& d : devs)
      if (d.desc.platform_index == p && d.desc.device_index == q) { chosen = &d; break; }
  } else {
    for (auto& d : devs)
      if (lower(d.desc.platform + ": " + d.desc.name).find(spec) != std::string::npos) {
        chosen = &d;
        break;
      }
  }
  if (!chosen)
    throw InputError("VPM_DEVICE='" + spec_in + "' matches no device; " + device_list_text(devs, why));
  if (!chosen->desc.fp64)
    throw InputError("VPM_DEVICE='" + spec_in + "' selects " + chosen->desc.label() +
                     ", which has no double precision (fp64); vpm computes in double");

  std::shared_ptr<Device> d(new Device());
  d->host_ = false;
  d->desc_ = chosen->desc;
  d->local_size_ = d->desc_.kind == DeviceKind::gpu ? 128 : 64;
  d->cl_ = std::make_unique<detail::DeviceCl>(*d, bc::device(chosen->id, true));
  return d;
}

Device& Device::current() {
  static std::mutex m;
  static std::shared_ptr<Device> dev;
  std::lock_guard<std::mutex> lock(m);
  if (!dev) {
    const char* env = std::getenv("VPM_DEVICE");
    dev = select(env ? env : "");
  }
  return *dev;
}

Device::Device() = default;
Device::~Device() = default;

detail::DeviceCl& Device::cl() {
  if (!cl_) throw std::logic_error("Device::cl() on the host device");
  return *cl_;
}

detail::DeviceCl::DeviceCl(const Device& o, const bc::device& d)
    : owner(o), device(d), context(device), queue(context, device) {}

std::string Device::name() const { return host_ ? std::string("host") : desc_.label(); }

size_t Device::padded(size_t n) const {
  size_t g = (n + local_size_ - 1) / local_size_ * local_size_;
  return std::max(g, local_size_);
}

bool Device::group_reduce() const {
  if (host_) return false;
  return group_reduce_override_ ? *group_reduce_override_ : desc_.kind != DeviceKind::cpu;
}

size_t Device::reduction_partials(size_t global) const {
  return group_reduce() ? padded(global) / local_size_ : padded(global);
}

size_t Device::combine_items() const { return group_reduce() ? local_size_ : 1; }

namespace detail {

void DeviceCl::launch(bc::kernel& k, size_t n) {
  size_t global = owner.padded(n);
  size_t local = owner.local_size();
  queue.enqueue_nd_range_kernel(k, 1, nullptr, &global, &local);
}

bc::kernel DeviceCl::kernel(const std::string& program, const std::string& kernel_name,
                            const std::string& options) {
  const std::string key = program + "|" + options + (owner.group_reduce() ? "|group" : "");
  std::lock_guard<std::mutex> lock(programs_mutex_);
  auto it = programs_.find(key);
  if (it == programs_.end()) {
    const auto& sources = detail::embedded_kernel_sources();
    auto s = sources.find(program);
    if (s == sources.end()) throw std::runtime_error("no embedded kernel program '" + program + "'");
    it = programs_.emplace(key, build_program("kernels/" + program + ".cl", s->second, options)).first;
  }
  return it->second.create_kernel(kernel_name);
}

namespace {

// The `#include "name.clh"` lines of a kernel source replaced by the embedded kernels/name.clh
// (one level: a shared header such as tet_locate.clh, which the host compiles too), each
// followed by a #line directive so that compiler messages keep the program's own line numbers.
std::string expand_includes(const std::string& program, const std::string& source) {
  static const std::string directive = "#include \"";
  std::istringstream in(source);
  std::string line, out;
  for (int number = 1; std::getline(in, line); ++number) {
    const size_t end = line.find('"', directive.size());
    if (line.rfind(directive, 0) != 0 || end == std::string::npos) {
      out += line + "\n";
      continue;
    }
    const std::string file = line.substr(directive.size(), end - directive.size());
    const auto& sources = embedded_kernel_sources();
    const auto it = file.size() > 4 && file.compare(file.size() - 4, 4, ".clh") == 0
                        ? sources.find(file.substr(0, file.size() - 4))
                        : sources.end();
    if (it == sources.end())
      throw DeviceError(program + ":" + std::to_string(number) + ": no embedded kernel header '" + file + "'");
    out += it->second + "\n#line " + std::to_string(number + 1) + "\n";
  }
  return out;
}

}  // namespace

bc::program DeviceCl::build_program(const std::string& name, const std::string& source, const std::string& options) {
  const std::string preamble =
      "#pragma OPENCL EXTENSION cl_khr_fp64 : enable\n"
      "typedef double real;\ntypedef double2 real2;\ntypedef double3 real3;\ntypedef double4 real4;\n";
  const std::string common = detail::embedded_kernel_sources().at("common");  // kernels/common.clh
  bc::program prog = bc::program::create_with_source(preamble + common + "\n#line 1\n" + expand_includes(name, source), context);
  std::string build_options = "-cl-std=CL1.2 -DLS=" + std::to_string(owner.local_size());
  if (owner.group_reduce()) build_options += " -DGROUP_REDUCE";
  if (!options.empty()) build_options += " " + options;
  try {
    prog.build(build_options);
  } catch (const bc::opencl_error& e) {
    // one line: the log's first non-empty lines (the first error and its context), joined by " | "
    std::istringstream log(prog.build_log());
    std::string line, first;
    for (int kept = 0; kept < 6 && std::getline(log, line);) {
      line = trim(line);
      if (line.empty()) continue;
      first += (kept++ ? " | " : "") + line;
    }
    throw DeviceError(name + ": OpenCL build failed on " + owner.name() + " (" + e.error_string() + ", options '" +
                      build_options + "'): " + (first.empty() ? "(empty build log)" : first));
  }
  return prog;
}

}  // namespace detail

void Device::check_buffer(unsigned long long bytes, const std::string& what) const {
  if (host_) return;
  const auto limit = std::min(desc_.max_alloc_bytes ? desc_.max_alloc_bytes : ~0ULL,
                              desc_.global_memory_bytes ? desc_.global_memory_bytes : ~0ULL);
  if (bytes <= limit) return;
  const bool one = desc_.max_alloc_bytes && desc_.max_alloc_bytes <= desc_.global_memory_bytes;
  throw DeviceError(what + ": a buffer of " + std::to_string(bytes) + " bytes is larger than " + name() +
                    (one ? " allows for one buffer (CL_DEVICE_MAX_MEM_ALLOC_SIZE = " : " has memory (") +
                    std::to_string(limit) + " bytes); use a smaller input or VPM_DEVICE=host");
}

std::string opencl_error_description(const std::exception& e) {
  const auto* cl = dynamic_cast<const bc::opencl_error*>(&e);
  if (!cl) return {};
  return "OpenCL error " + std::to_string(cl->error_code()) + " (" + cl->error_string() + ")";
}

}  // namespace vpm
