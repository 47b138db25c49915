#pragma once
// Scratch folders for tests that write files (under the build tree's tests/tmp).
#include <string>

namespace vpm::test {

/// VPM_TEST_TMP/name, emptied (made if absent); returns its path.
std::string fresh_dir(const std::string& name);

}  // namespace vpm::test
