// Writing tables from tests: the offline writer throws InputError; these helpers turn
// that into a Result so that tests can assert on success and on the message alike.
#pragma once

#include <filesystem>

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

}  // namespace shtool::test
