// shtool: one executable, one subcommand per file in src/cli/. Each file registers its
// options with setup_<name>(sub) and does its work through the libraries; errors are
// turned into a message and an exit code here, in one place.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <new>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "shtool/version.h"

int main(int argc, char** argv) {
  CLI::App app{"shtool: spherical-harmonics precomputation (lobe search, ZH fitting, tensors) "
               "lighting projection, and checks of the runtime library"};
  app.set_version_flag("--version", std::string("shtool ") + shtool::kVersion);
  // 0..1 rather than exactly 1, so that an unknown subcommand is reported by name.
  app.require_subcommand(0, 1);
  // The subcommands in the order --help lists them, each with its one-line help; each
  // file's setup_<name> adds its options and its callback.
  struct Subcommand {
    const char* name;
    const char* help;
    void (*setup)(CLI::App*);
  };
  using namespace shtool::cli;
  static constexpr Subcommand kSubcommands[] = {
      {"eval", "Print all N^2 real SH values at a direction (JSON)", setup_eval},
      {"inspect", "Print a table's header and a summary of its arrays, verifying every checksum", setup_inspect},
      {"gen-tensors", "Generate tensor and rotation tables", setup_gen_tensors},
      {"gen-shader", "Generate a GLSL or HLSL include file of an SH operation", setup_gen_shader},
      {"render", "Render a mesh shaded by its transfer or ZH fit under SH lighting", setup_render},
      {"deform", "Rotate a ZH fit's lobes from its rest mesh into a posed mesh's frames", setup_deform},
      {"fit-wrinkles", "Simulate the sinusoidal-groove wrinkle model and fit its (x, d) map of ZH lobes", setup_fit_wrinkles},
      {"fit-glossy", "Glossy PRT on a mesh: transfer matrices, BRDF-specialised by an SVD, each row fitted with ZH lobes", setup_fit_glossy},
      {"rotate", "Rotate an SH vector: g(w) = f(R^-1 w) (JSON)", setup_rotate},
      {"product", "Product of 2 to 8 SH functions truncated to order N (JSON in, JSON out). Input: {\"inputs\": [[N^2 coefficients], ...]}; output: {\"order\": N, \"coefficients\": [...]}", setup_product},
      {"fit-zh", "Simulate diffuse PRT transfer on a mesh and fit ZH lobes per vertex", setup_fit_zh},
      {"merge", "Join the partial tables of fit-zh --shard K/N or bake-probes --shard K/N into one table", setup_merge},
      {"search-lobes", "Genetic search for sparse zonal-harmonic factorisations ([1]): lobe directions whose A^_l = Y_l^-1 has many zeros, per band or shared across bands. See docs/lobes.md.", setup_search_lobes},
      {"project-env", "Project an HDR environment image (equirect or cubemap) onto SH", setup_project_env},
      {"light", "Analytic lights (directional, cone, sphere, hemisphere, constant) as SH", setup_light},
      {"transform-splats", "Convert a 3D Gaussian Splatting scene between .ply, .spz, .gltf and .glb, optionally rotated, scaled and moved, its SH colours included", setup_transform_splats},
      {"export-light", "Write SH lighting (project-env / light JSON) in an engine's convention", setup_export_light},
      {"import-light", "Read SH lighting in an engine's convention into shtool's lighting JSON", setup_import_light},
      {"bake-probes", "Bake a grid of SH irradiance probes (incident radiance, RGB) from a glTF or OBJ scene by path tracing", setup_bake_probes},
      {"export-web", "Write a folder with a web page (three.js) showing a mesh shaded by its ZH fit, the light turning live", setup_export_web},
  };
  for (const Subcommand& s : kSubcommands) s.setup(app.add_subcommand(s.name, s.help));
  // CLI11 reads an empty value as 0 for a number (--threads '' ran on every core, --seed ''
  // used seed 0): no option of shtool takes an empty value, and one is most often a shell
  // variable that was never set.
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool inline_empty = arg.size() > 3 && arg.substr(0, 2) == "--" && arg.back() == '=';
    if (!arg.empty() && !inline_empty) continue;
    const std::string option = inline_empty                     ? std::string(arg.substr(0, arg.size() - 1))
                               : i > 1 && argv[i - 1][0] == '-' ? std::string(argv[i - 1])
                                                                : "argument " + std::to_string(i);
    std::cerr << "shtool: error: " << option << " is given an empty value (an unset shell variable?)\n";
    return 1;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help/--version exit 0, printed by CLI11; every command-line error is reported as
    // the other user errors are (the README's "shtool: error: ..."), exit 1.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "shtool: error: " << e.what() << "\nRun with --help for more information.\n";
    return 1;
  } catch (const shtool::InputError& e) {
    std::cerr << "shtool: error: " << e.what() << '\n';
    return 1;
  } catch (const std::bad_alloc&) {
    // An input too large for this machine (the jobs refuse what they can estimate first).
    std::cerr << "shtool: error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "shtool: internal error: " << e.what() << '\n';
    return 3;
  }
  if (app.get_subcommands().empty()) {
    std::cerr << "shtool: error: a subcommand is required\n" << app.help();
    return 1;
  }
  // eval, rotate, product and inspect print their result: a full disk or a closed stdout
  // behind `> result.json` must fail the command, not leave a cut file and exit 0.
  std::cout.flush();
  if (std::fflush(stdout) != 0 || std::ferror(stdout) || !std::cout) {
    const int err = errno;
    std::cerr << "shtool: error: cannot write the result to standard output"
              << (err ? std::string(": ") + std::strerror(err) : std::string()) << '\n';
    return 1;
  }
  return 0;
}
