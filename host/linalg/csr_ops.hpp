#pragma once
// Private: CSR building blocks of the multigrid setup (linalg/amg.cpp): transpose and the
// sparse product split into a symbolic step (pattern, once) and a numeric step (values).
#include "vpm/sparse.hpp"

namespace vpm::detail {

/// A^T (pattern and values; columns sorted).
CsrMatrix csr_transpose(const CsrMatrix& a);

/// The pattern of A B (row_ptr, col sorted; val zero-filled). Every structurally possible
/// entry is kept, so the pattern depends on the patterns of A and B only. Rows in blocks on the
/// host threads (the result does not depend on their number).
CsrMatrix spgemm_pattern(const CsrMatrix& a, const CsrMatrix& b);

/// Fills c.val with the values of A B, c holding spgemm_pattern(a, b), rows in blocks on the
/// host threads, each row summed in the same order as one serial pass. `pos` is scratch
/// (resized to b.cols; the other threads allocate their own).
void spgemm_values(const CsrMatrix& a, const CsrMatrix& b, CsrMatrix& c, std::vector<int>& pos);

}  // namespace vpm::detail
