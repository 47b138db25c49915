// Links the installed vpm and checks one result: the unit corner tet has volume 1/6.
#include <vpm/config.hpp>
#include <vpm/device.hpp>
#include <vpm/geometry.hpp>

#include <cmath>
#include <cstdio>

int main() {
  vpm::Points x(4, 3);
  x << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  vpm::Tets t(1, 4);
  t << 0, 1, 2, 3;
  auto host = vpm::Device::host();
  const double v = vpm::tet_volumes(*host, x, t)(0);
  std::printf("vpm %s: volume %.17g\n", VPM_VERSION, v);
  return std::fabs(v - 1.0 / 6.0) < 1e-15 ? 0 : 1;
}
