// Internal to the runtime: the sparsity structure of X90 (the rotation by +90 degrees
// about x) that the zxzxz and Taylor paths rely on. Band l of X90 maps the four classes
// of m (sign, parity) onto each other by square dense blocks of sizes floor(l/2) and
// ceil(l/2) (+1 for m >= 0 even), so the non-zeros of a row lie in one class of columns,
// lo, lo + 2, ..., hi. A table is checked against it when it is read (a corrupted table
// is an error there, never a crash later) and the rotation packs its rows by it.
#pragma once

#include <optional>

namespace shtool::detail {

// Number of non-zeros in row j (m = j - l) of band l of X90, and of X90^T.
constexpr int x90_row_length(int l, int j) {
  const int m = j - l;
  if (l & 1) return (m < 0 && !(m & 1)) ? (l - 1) / 2 : (l + 1) / 2;
  return (m >= 0 && !(m & 1)) ? l / 2 + 1 : l / 2;
}

// Band-relative columns lo, lo + 2, ..., hi read by one row.
struct X90Run {
  int lo = 0, hi = 0;
};

// The run of row r of band l, the row given by at(c) for band-relative columns
// c = 0..2l; empty when the row breaks the structure (no non-zero, a non-zero outside
// the class of the first one, or a class of the wrong length).
template <class At>
std::optional<X90Run> x90_row_run(int l, int r, At at) {
  const int size = 2 * l + 1;
  int nz = -1;
  for (int c = 0; c < size && nz < 0; ++c)
    if (at(c) != 0.0) nz = c;
  if (nz < 0) return std::nullopt;
  const int m = nz - l, odd = m & 1;
  const int m_lo = m < 0 ? -l + (((-l) & 1) != odd) : odd;
  const int m_hi = m < 0 ? -1 - (odd == 0) : l - ((l & 1) != odd);
  const X90Run run{m_lo + l, m_hi + l};
  if ((run.hi - run.lo) / 2 + 1 != x90_row_length(l, r)) return std::nullopt;
  for (int c = 0; c < size; ++c)
    if (at(c) != 0.0 && (c < run.lo || c > run.hi || (c - run.lo) % 2)) return std::nullopt;
  return run;
}

}  // namespace shtool::detail
