// shtool inspect TABLE [--json]: header, summary and checksum verification of a table.
// The whole table is loaded through the runtime's validating loader, so a table this
// command accepts is one an engine accepts.
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "shtool/table.h"

namespace shtool::cli {
namespace {

using json = nlohmann::json;

struct InspectOptions {
  std::string table;
  bool as_json = false;
};

// min, max (over finite values for floats: a NaN would make both meaningless) and the
// count of non-finite values; min/max are null for an empty (or all non-finite) array.
template <class T>
json array_stats(const TableArray& a) {
  const std::vector<T> v = a.values<T>();
  json out = json::object();
  bool any = false;
  T lo{}, hi{};
  std::size_t nonfinite = 0;
  for (const T& x : v) {
    if constexpr (std::is_floating_point_v<T>) {
      if (!std::isfinite(x)) {
        ++nonfinite;
        continue;
      }
    }
    if (!any || x < lo) lo = x;
    if (!any || x > hi) hi = x;
    any = true;
  }
  // f32 is shown as the exact double of the float.
  using Shown = std::conditional_t<std::is_same_v<T, float>, double, T>;
  out["min"] = any ? json(static_cast<Shown>(lo)) : json(nullptr);
  out["max"] = any ? json(static_cast<Shown>(hi)) : json(nullptr);
  if constexpr (std::is_floating_point_v<T>) out["nonfinite"] = nonfinite;
  return out;
}

json array_summary(const TableArray& a) {
  json s = {{"name", a.name}, {"dtype", dtype_name(a.dtype)}, {"shape", a.shape},
            {"elements", a.element_count()}};
  json stats;
  switch (a.dtype) {
    case DType::f64: stats = array_stats<double>(a); break;
    case DType::f32: stats = array_stats<float>(a); break;
    case DType::i32: stats = array_stats<std::int32_t>(a); break;
    case DType::u32: stats = array_stats<std::uint32_t>(a); break;
    case DType::i64: stats = array_stats<std::int64_t>(a); break;
    case DType::u64: stats = array_stats<std::uint64_t>(a); break;
    case DType::u8: stats = array_stats<std::uint8_t>(a); break;
  }
  s.update(stats);
  return s;
}

std::string shape_text(const json& shape) {
  std::string s = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + shape[i].dump();
  return s + "]";
}

void run_inspect(const InspectOptions& opt) {
  TableFileInfo info;
  auto result = read_table(opt.table, {}, &info);
  if (!result) throw InputError(result.error().message);
  const Table& t = result.value();
  // The reader refuses JSON nested deep enough to exhaust the stack, so dump() is safe.
  const json header = json::parse(info.header_json);

  json arrays = json::array();
  for (const TableArray& a : t.arrays) arrays.push_back(array_summary(a));
  const char* encoding = info.encoding == TableEncoding::binary ? "binary" : "json";
  const json summary = {{"file", opt.table},
                        {"encoding", encoding},
                        {"file_size", info.file_size},
                        {"kind", t.kind},
                        {"kind_version", t.kind_version},
                        {"order", t.order},
                        {"arrays", arrays}};
  if (opt.as_json) {
    // read_table only returns a table whose header and array CRCs all verified.
    print_json({{"header", header},
                {"summary", summary},
                {"checksums_ok", true},
                {"header_checksummed", info.encoding == TableEncoding::binary}});
    return;
  }
  std::cout << "file: " << opt.table << " (" << encoding << ", " << info.file_size << " bytes)\n"
            << "kind: " << t.kind << " (version " << t.kind_version << "), order " << t.order << '\n'
            << "header:\n"
            << header.dump(2) << '\n'
            << "arrays:\n";
  for (const json& a : arrays) {
    std::cout << "  " << a["name"].get<std::string>() << "  " << a["dtype"].get<std::string>() << "  shape "
              << shape_text(a["shape"]) << "  min " << a["min"].dump() << "  max " << a["max"].dump();
    if (a.contains("nonfinite") && a["nonfinite"].get<std::size_t>() > 0)
      std::cout << "  non-finite " << a["nonfinite"].get<std::size_t>();
    std::cout << '\n';
  }
  // A JSON table's header fields carry no checksum (only its arrays do): say what was
  // verified, not more.
  if (info.encoding == TableEncoding::binary)
    std::cout << "checksums: OK (header and " << t.arrays.size() << " arrays)\n";
  else
    std::cout << "checksums: OK (" << t.arrays.size() << " arrays; a JSON table's header has no checksum)\n";
}

}  // namespace

void setup_inspect(CLI::App* sub) {
  auto opt = std::make_shared<InspectOptions>();
  sub->add_option("table", opt->table, "table file (binary or JSON encoding)")->required();
  sub->add_flag("--json", opt->as_json, "print one JSON object: header, summary, checksums_ok");
  sub->callback([opt]() { run_inspect(*opt); });
}

}  // namespace shtool::cli
