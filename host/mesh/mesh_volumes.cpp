#include "mesh/mesh_volumes.hpp"

#include <boost/compute/algorithm/copy.hpp>
#include <boost/compute/container/vector.hpp>

#include "core/device_cl.hpp"
#include "vpm/device.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"

namespace vpm::detail {

namespace bc = boost::compute;

struct MeshVolumes::Impl {
  Device& dev;
  const Tets& tets;
  bc::vector<int> dtets, offset, tet_of;  // the incidence: at the first dual_volumes
  bc::vector<double> x, vol, dual;

  Impl(Device& d, const Tets& t)
      : dev(d),
        tets(t),
        dtets(t.data(), t.data() + t.size(), d.cl().queue),
        offset(d.cl().context),
        tet_of(d.cl().context),
        x(d.cl().context),
        vol(static_cast<size_t>(t.rows()), d.cl().context),
        dual(d.cl().context) {}

  // Uploads x and runs tet_volumes into `vol`.
  void volumes(const Points& p) {
    auto& q = dev.cl().queue;
    if (x.size() != static_cast<size_t>(p.size())) x = bc::vector<double>(static_cast<size_t>(p.size()), dev.cl().context);
    bc::copy(p.data(), p.data() + p.size(), x.begin(), q);
    auto k = dev.cl().kernel("geometry", "tet_volumes");
    k.set_args(static_cast<int>(tets.rows()), x, dtets, vol);
    dev.cl().launch(k, static_cast<size_t>(tets.rows()));
  }
};

MeshVolumes::MeshVolumes(Device& device, const Tets& tets)
    : tets_(tets), impl_(device.is_host() ? nullptr : std::make_unique<Impl>(device, tets)) {}

MeshVolumes::~MeshVolumes() = default;

Eigen::VectorXd MeshVolumes::tet_volumes(const Points& x) {
  if (!impl_) return vpm::tet_volumes(x, tets_);
  Impl& s = *impl_;
  Eigen::VectorXd out(s.tets.rows());
  if (s.tets.rows() == 0) return out;
  s.volumes(x);
  bc::copy(s.vol.begin(), s.vol.end(), out.data(), s.dev.cl().queue);
  return out;
}

Eigen::VectorXd MeshVolumes::dual_volumes(const Points& x) {
  if (!impl_) return vpm::dual_volumes(x, tets_);
  Impl& s = *impl_;
  auto& q = s.dev.cl().queue;
  const int n = static_cast<int>(x.rows());
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
  if (s.tets.rows() == 0 || n == 0) return out;
  if (s.offset.size() != static_cast<size_t>(n) + 1) {
    const Incidence inc = vertex_tet_incidence(n, s.tets);
    s.offset = bc::vector<int>(inc.offset.begin(), inc.offset.end(), q);
    s.tet_of = bc::vector<int>(inc.tet_of.begin(), inc.tet_of.end(), q);
    s.dual = bc::vector<double>(static_cast<size_t>(n), s.dev.cl().context);
  }
  s.volumes(x);
  auto k = s.dev.cl().kernel("geometry", "dual_volumes");
  k.set_args(n, s.offset, s.tet_of, s.vol, s.dual);
  s.dev.cl().launch(k, static_cast<size_t>(n));
  bc::copy(s.dual.begin(), s.dual.end(), out.data(), q);
  return out;
}

}  // namespace vpm::detail
