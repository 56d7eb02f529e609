// The table reader on arbitrary bytes, both encodings: with checksums verified (what an
// engine runs) and without, so that mutated headers and arrays get past the CRCs to the
// structural checks. Whatever the bytes: no crash, no hang, no partial table.
#include <cstddef>
#include <cstdint>
#include <span>

#include "shtool/table.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  for (bool verify : {true, false}) {
    shtool::TableFileInfo info;
    const shtool::Result<shtool::Table> t = shtool::read_table_bytes(bytes, "fuzz", {}, &info, {verify});
    if (t) {
      // A table that loads is whole: every array holds the bytes its shape needs.
      for (const shtool::TableArray& a : t.value().arrays)
        if (a.data.size() != a.element_count() * shtool::dtype_size(a.dtype)) __builtin_trap();
    }
  }
  return 0;
}
