#include "cli_common.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iostream>

namespace shtool::cli {

std::vector<double> parse_number_list(const std::string& text, const std::string& what) {
  std::vector<double> values;
  std::size_t pos = 0;
  while (true) {
    const std::size_t comma = text.find(',', pos);
    const std::string field = text.substr(pos, comma == std::string::npos ? std::string::npos
                                                                          : comma - pos);
    const char* begin = field.c_str();
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    while (end && (*end == ' ' || *end == '\t')) ++end;
    if (field.find_first_not_of(" \t") == std::string::npos || end == begin || *end != '\0')
      throw InputError(what + ": '" + field + "' is not a number (expected comma-separated numbers, got '" +
                      text + "')");
    // ERANGE on underflow still yields the nearest (subnormal or zero) value, which is
    // what the user wrote; only overflow to infinity is an error.
    if (!std::isfinite(v))
      throw InputError(what + ": '" + field + "' is not a finite number");
    values.push_back(v);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return values;
}

std::optional<view::Camera> parse_camera(const std::string& text) {
  if (text.empty()) return std::nullopt;
  const std::vector<double> v = parse_number_list(text, "--camera");
  if (v.size() != 9) throw InputError("--camera takes nine numbers: eye,target,up");
  return view::Camera{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]}};
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::size_t pos = 0;
  while (true) {
    const std::size_t comma = text.find(',', pos);
    items.push_back(text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos));
    if (comma == std::string::npos) return items;
    pos = comma + 1;
  }
}

void print_json(const nlohmann::json& value) { std::cout << value.dump() << '\n'; }

}  // namespace shtool::cli

namespace shtool::cli {

CLI::Option* add_up_option(CLI::App* app, UpAxis& target) {
  return add_enum_option(app, "--up", target, up_axis_names(),
                         "an OBJ's up axis: y (Blender's OBJ default; turned into shtool's z-up frame) or z "
                         "(taken as written); a glTF is +Y up by its specification",
                         "y");
}

CLI::Option* add_seed_option(CLI::App* app, std::uint64_t& target, const std::string& help) {
  // CLI11 saturates a number past 2^64 - 1 to that value: two different seeds would bake
  // the same. Digits only, and within range.
  static const CLI::Validator unsigned_text(
      [](std::string& v) {
        if (v.find('-') != std::string::npos) return std::string("must not be negative");
        errno = 0;
        char* end = nullptr;
        std::strtoull(v.c_str(), &end, 10);
        if (errno == ERANGE) return std::string("must be at most 18446744073709551615 (2^64 - 1)");
        return std::string();
      },
      "UINT");
  return app->add_option("--seed", target, help)->check(unsigned_text)->capture_default_str();
}

CLI::Option* add_threads_option(CLI::App* app, int& target) {
  return app->add_option("--threads", target, "worker threads (0: all cores)")->capture_default_str();
}

CLI::Option* add_table_format_option(CLI::App* app, TableEncoding& target, const std::string& help) {
  return add_enum_option(app, "--format", target, {{"binary", TableEncoding::binary}, {"json", TableEncoding::json}},
                         help, "binary");
}

}  // namespace shtool::cli
