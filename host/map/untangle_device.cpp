// OpenCL evaluation of the untangling energy (see map/untangle_problem.hpp).
#include <Eigen/Dense>
#include <algorithm>
#include <limits>

#include <boost/compute/container/vector.hpp>

#include "map/untangle_problem.hpp"
#include "core/device_cl.hpp"
#include "vpm/device.hpp"

namespace vpm {

namespace bc = boost::compute;

struct UntangleDeviceEval::State {
  Device& dev;
  int n = 0, m = 0, nfree = 0;
  bc::vector<int> tv, off, slot;
  bc::vector<double> rinv, w, x, e, d, gt, g;
  bc::kernel ktet, kgather;
  std::vector<double> he, hd;

  State(Device& device, int num_vertices, int active, int free)
      : dev(device), n(num_vertices), m(active), nfree(free), tv(device.cl().context), off(device.cl().context),
        slot(device.cl().context), rinv(device.cl().context), w(device.cl().context), x(device.cl().context),
        e(device.cl().context), d(device.cl().context), gt(device.cl().context), g(device.cl().context) {}
};

UntangleDeviceEval::UntangleDeviceEval(Device& device, const UntangleProblem& p, int num_vertices)
    : s_(std::make_unique<State>(device, num_vertices, static_cast<int>(p.active.size()),
                                 static_cast<int>(p.free_vertices.size()))) {
  State& s = *s_;
  auto& q = s.dev.cl().queue;
  const Tets& t = *p.tets;
  const int m = s.m, nfree = s.nfree;
  std::vector<int> htv(4 * static_cast<size_t>(m));
  std::vector<double> hr(9 * static_cast<size_t>(m));
  std::vector<std::vector<int>> per(nfree);
  for (int a = 0; a < m; ++a) {
    for (int k = 0; k < 4; ++k) {
      const int v = t(p.active[a], k);
      htv[4 * a + k] = v;
      if (p.var[v] >= 0) per[p.var[v] / 3].push_back(12 * a + 3 * k);
    }
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) hr[9 * a + 3 * r + c] = p.rinv[a](r, c);
  }
  std::vector<int> hoff(nfree + 1, 0), hslot;
  for (int f = 0; f < nfree; ++f) {
    hoff[f + 1] = hoff[f] + static_cast<int>(per[f].size());
    hslot.insert(hslot.end(), per[f].begin(), per[f].end());
  }
  if (hslot.empty()) hslot.push_back(0);
  s.tv.assign(htv.begin(), htv.end(), q);
  s.rinv.assign(hr.begin(), hr.end(), q);
  s.w.assign(p.weight.begin(), p.weight.end(), q);
  s.off.assign(hoff.begin(), hoff.end(), q);
  s.slot.assign(hslot.begin(), hslot.end(), q);
  s.x.resize(3 * static_cast<size_t>(s.n), q);
  s.e.resize(m, q);
  s.d.resize(m, q);
  s.gt.resize(12 * static_cast<size_t>(m), q);
  s.g.resize(std::max(3 * nfree, 1), q);
  s.he.resize(m);
  s.hd.resize(m);
  s.ktet = s.dev.cl().kernel("untangle", "untangle_tet");
  s.kgather = s.dev.cl().kernel("untangle", "untangle_gather");
  // eps (1) and want_grad (3) are set per evaluation
  s.ktet.set_args(m, 0.0, p.theta, 0, s.tv, s.rinv, s.w, s.x, s.e, s.d, s.gt);
  s.kgather.set_args(nfree, s.off, s.slot, s.gt, s.g);
}

UntangleDeviceEval::~UntangleDeviceEval() = default;

UntangleEval UntangleDeviceEval::run(const Points& xs, double eps, Eigen::VectorXd* grad) {
  State& s = *s_;
  auto& q = s.dev.cl().queue;
  q.enqueue_write_buffer(s.x.get_buffer(), 0, sizeof(double) * 3 * s.n, xs.data());
  s.ktet.set_arg(1, eps);
  s.ktet.set_arg(3, grad ? 1 : 0);
  s.dev.cl().launch(s.ktet, s.m);
  if (grad && s.nfree > 0) {
    s.dev.cl().launch(s.kgather, s.nfree);
    q.enqueue_read_buffer_async(s.g.get_buffer(), 0, sizeof(double) * 3 * s.nfree, grad->data());
  }
  q.enqueue_read_buffer_async(s.e.get_buffer(), 0, sizeof(double) * s.m, s.he.data());
  q.enqueue_read_buffer_async(s.d.get_buffer(), 0, sizeof(double) * s.m, s.hd.data());
  q.finish();
  UntangleEval out;
  out.min_det = std::numeric_limits<double>::infinity();
  for (int a = 0; a < s.m; ++a) {
    out.energy += s.he[a];
    out.min_det = std::min(out.min_det, s.hd[a]);
    if (s.hd[a] <= 0) ++out.nonpositive;
  }
  return out;
}

}  // namespace vpm
