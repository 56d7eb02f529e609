// Tables in tests. The offline writer throws InputError; try_write turns that into a
// Result so that tests can assert on success and on the message alike. expect_same_table
// is what a round trip must give back.
#pragma once

#include <cstddef>
#include <filesystem>

#include <gtest/gtest.h>

#include "common/input_error.h"
#include "common/table_writer.h"
#include "shtool/result.h"
#include "shtool/table.h"

namespace shtool::test {

inline Result<Ok> try_write(const Table& t, const std::filesystem::path& p,
                            TableEncoding encoding = TableEncoding::binary) {
  try {
    write_table(t, p, encoding, NonFinite::keep);  // the format's own tests: specials too
    return Ok{};
  } catch (const InputError& e) {
    return Error{e.what()};
  }
}

// The same table: header fields, and every array's name, dtype, shape and bytes.
inline void expect_same_table(const Table& a, const Table& b) {
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.kind_version, b.kind_version);
  EXPECT_EQ(a.order, b.order);
  EXPECT_EQ(a.generator, b.generator);
  EXPECT_EQ(a.meta, b.meta);
  ASSERT_EQ(a.arrays.size(), b.arrays.size());
  for (std::size_t i = 0; i < a.arrays.size(); ++i) {
    const TableArray &x = a.arrays[i], &y = b.arrays[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.dtype, y.dtype) << x.name;
    EXPECT_EQ(x.shape, y.shape) << x.name;
    // Byte equality = every value's exact bits (sign of zero, denormals, NaN payloads).
    EXPECT_TRUE(x.data == y.data) << "array '" << x.name << "' bytes differ after the round trip";
  }
}

}  // namespace shtool::test
