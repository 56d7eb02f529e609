// The folders export-web copies its page from. The build-tree and installed paths come
// from CMake (SHTOOL_BUILD_THREE_DIR, SHTOOL_SOURCE_WEB_DIR, SHTOOL_INSTALL_WEB_DIR).
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "web/web_assets.h"

#ifndef SHTOOL_BUILD_THREE_DIR
#define SHTOOL_BUILD_THREE_DIR ""
#endif
#ifndef SHTOOL_SOURCE_WEB_DIR
#define SHTOOL_SOURCE_WEB_DIR ""
#endif
#ifndef SHTOOL_INSTALL_WEB_DIR
#define SHTOOL_INSTALL_WEB_DIR ""
#endif

namespace shtool::web {
namespace {

std::filesystem::path first_with(const char* env, std::initializer_list<std::filesystem::path> candidates,
                                 const char* marker) {
  std::error_code ec;
  if (const char* e = std::getenv(env); e && *e) return std::filesystem::path(e);
  for (const std::filesystem::path& c : candidates)
    if (!c.empty() && std::filesystem::is_regular_file(c / marker, ec)) return c;
  return {};
}

}  // namespace

std::filesystem::path three_package_dir() {
  return first_with("SHTOOL_THREE_DIR",
                    {std::filesystem::path(SHTOOL_BUILD_THREE_DIR),
                     std::filesystem::path(SHTOOL_INSTALL_WEB_DIR).empty()
                         ? std::filesystem::path()
                         : std::filesystem::path(SHTOOL_INSTALL_WEB_DIR) / "three"},
                    "package.json");
}

std::filesystem::path web_source_dir() {
  return first_with("SHTOOL_WEB_DIR",
                    {std::filesystem::path(SHTOOL_SOURCE_WEB_DIR), std::filesystem::path(SHTOOL_INSTALL_WEB_DIR)},
                    "export-web.html");
}

}  // namespace shtool::web
