// Shared pieces of the thin CLI layer: the one user-error type, strict parsing of
// numeric lists, and JSON printing with round-trip precision.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace CLI {
class App;
}

namespace shtool::cli {

// Bad input from the user (malformed option, unreadable file, invalid table...).
// main() turns it into "shtool: error: <message>" on stderr and exit code 1.
class UserError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Parses "a,b,c" into finite doubles; `what` names the option in error messages.
// Throws UserError on empty fields, trailing garbage, NaN or infinity.
std::vector<double> parse_number_list(const std::string& text, const std::string& what);

// Prints JSON to stdout followed by a newline. nlohmann-json writes doubles with the
// shortest representation that reads back to the same bits (round-trip exact).
void print_json(const nlohmann::json& value);

// Each subcommand registers itself here; see main.cpp.
void setup_eval(CLI::App& app);
void setup_inspect(CLI::App& app);
void setup_gen_tensors(CLI::App& app);
void setup_rotate(CLI::App& app);
void setup_product(CLI::App& app);
void setup_fit_zh(CLI::App& app);
void setup_search_lobes(CLI::App& app);

}  // namespace shtool::cli
