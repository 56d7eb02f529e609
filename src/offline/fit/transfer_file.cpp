#include "fit/transfer_file.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "common/finite.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "fit/mesh.h"
#include "shtool/sh.h"

namespace shtool::fit {
namespace {

// Transfer coefficients are O(1) (radiance transfer of a unit light); far larger inputs
// would overflow the squared norms of the fit (about 1e154).
constexpr double kMaxTransferMagnitude = 1e100;

}  // namespace

// {"order": n, "vectors": [[n^2 numbers], ...]}
std::vector<double> parse_transfer_json(std::string_view text, const std::filesystem::path& path_in, int& order,
                                        TransferMeshRecord* record) {
  const std::string path = path_in.string();
  const nlohmann::json doc = parse_json_input(text, path_in, "--transfer");
  if (!doc.is_object() || !doc.contains("order") || !doc.at("order").is_number_integer())
    throw InputError("--transfer '" + path + "': expected {\"order\": n, \"vectors\": [[n^2 numbers], ...]}");
  if (doc.contains(kMeshUpKey) && (!doc.at(kMeshUpKey).is_string() || (doc.at(kMeshUpKey) != "y" && doc.at(kMeshUpKey) != "z")))
    throw InputError("--transfer '" + path + "': \"" + kMeshUpKey + "\" must be \"y\" or \"z\"");
  if (doc.contains("mesh_crc32") && (!doc.at("mesh_crc32").is_number_unsigned() ||
                                     doc.at("mesh_crc32").get<std::uint64_t>() > 0xFFFFFFFFu))
    throw InputError("--transfer '" + path + "': \"mesh_crc32\" must be an unsigned 32-bit integer");
  const EnumNames<NormalSource>& normal_names = normal_source_names();
  if (doc.contains("normals") && std::none_of(normal_names.begin(), normal_names.end(),
                                              [&](const auto& n) { return doc.at("normals") == n.first; }))
    throw InputError("--transfer '" + path + "': \"normals\" must be \"auto\", \"file\" or \"computed\"");
  if (record) {
    record->mesh_up = doc.contains(kMeshUpKey) ? doc.at(kMeshUpKey).get<std::string>() : std::string();
    if (doc.contains("mesh_crc32")) record->mesh_crc32 = doc.at("mesh_crc32").get<std::uint32_t>();
    record->normals = doc.contains("normals") ? doc.at("normals").get<std::string>() : std::string();
  }
  const nlohmann::json& o = doc.at("order");
  const std::int64_t order64 = o.is_number_unsigned()
                                   ? (o.get<std::uint64_t>() > static_cast<std::uint64_t>(kMaxOrder) ? -1 : o.get<std::int64_t>())
                                   : o.get<std::int64_t>();
  if (order64 < 1 || order64 > kMaxOrder)
    throw InputError("--transfer '" + path + "': order " + o.dump() + " is not supported (1.." +
                     std::to_string(kMaxOrder) + ")");
  order = static_cast<int>(order64);
  if (!doc.contains("vectors") || !doc.at("vectors").is_array() || doc.at("vectors").empty())
    throw InputError("--transfer '" + path + "': \"vectors\" must be a non-empty array");
  const std::size_t n2 = sh_count(order);
  std::vector<double> values;
  std::size_t v = 0;
  for (const nlohmann::json& vec : doc.at("vectors")) {
    if (!vec.is_array() || vec.size() != n2)
      throw InputError("--transfer '" + path + "': vector " + std::to_string(v) + " must have " +
                      std::to_string(n2) + " numbers (order " + std::to_string(order) + ")");
    for (const nlohmann::json& x : vec) {
      if (!x.is_number()) throw InputError("--transfer '" + path + "': vector " + std::to_string(v) + " has a non-number");
      const double d = x.get<double>();
      if (!std::isfinite(d)) throw InputError("--transfer '" + path + "': vector " + std::to_string(v) + " is not finite");
      if (std::abs(d) > kMaxTransferMagnitude)
        throw InputError("--transfer '" + path + "': vector " + std::to_string(v) +
                         " has a coefficient beyond 1e100 in magnitude, more than the fit handles (its squared "
                         "norms would overflow)");
      values.push_back(d);
    }
    ++v;
  }
  return values;
}


// The --save-transfer output, in the --transfer format.
std::string transfer_json(const std::vector<double>& transfer, int order, UpAxis up, std::uint32_t mesh_crc32,
                          std::string_view normals) {
  const std::size_t n2 = sh_count(order);
  nlohmann::json doc = {{"order", order},
                        {kMeshUpKey, up_axis_name(up)},
                        {"mesh_crc32", mesh_crc32},
                        {"normals", normals},
                        {"vectors", nlohmann::json::array()}};
  for (std::size_t v = 0; v < transfer.size() / n2; ++v)
    doc["vectors"].push_back(std::vector<double>(transfer.begin() + v * n2, transfer.begin() + (v + 1) * n2));
  return dump_finite(doc, "--save-transfer") + "\n";
}

}  // namespace shtool::fit
