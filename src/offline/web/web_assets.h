// Where export-web copies its page from: three.js's npm package and shtool's own page files.
#pragma once

#include <filesystem>

namespace shtool::web {

// The three.js package (three@0.187.0: its package.json, build/ and examples/):
// $SHTOOL_THREE_DIR, else the build tree's node_consumers/node_modules/three, else the
// installed share/shtool/web/three. Empty when none has three's package.json.
std::filesystem::path three_package_dir();
// shtool's page files (export-web.html, shtool-three.js): $SHTOOL_WEB_DIR, else the source
// tree's web/, else the installed share/shtool/web. Empty when none has them.
std::filesystem::path web_source_dir();

}  // namespace shtool::web
