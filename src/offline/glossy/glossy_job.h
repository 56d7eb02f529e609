// fit-glossy as a library job: glossy LDPRT on a mesh ([4] Sec. 3.2). The BRDF matrix B
// (Eq. 14) and its truncated SVD, the transfer matrix of every vertex and its
// BRDF-specialised rows M' (Eq. 15), a ZH fit of each row, written as a glossy-zh table
// (shtool/glossy.h loads it, `shtool render --shading glossy` shows it) and, optionally, a
// JSON summary. docs/ldprt.md, "Glossy transfer".
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "fit/mesh.h"
#include "fit/zh_fit.h"
#include "glossy/brdf.h"

namespace shtool::glossy {

struct GlossyRequest {
  std::filesystem::path mesh;  // OBJ or glTF
  std::filesystem::path out;   // glossy-zh table
  std::filesystem::path json;  // optional summary
  Brdf brdf;
  int order = 4;             // [4] Fig. 4: n = 4
  // n_b. [4] Fig. 4 keeps 3 (the m = 0 mode and one +-m pair of B); with so few the
  // truncated B leaks light from below a face's horizon into it, and faces turned from the
  // sky go negative (a third of spot's covered pixels under the demo sky). 6 keeps two
  // pairs and the next m = 0 mode: at twice the rows the image is within 0.09 of the full
  // matrices' (0.26 with 3) and no more negative than theirs (docs/ldprt.md).
  int terms = 6;
  int lobes = 3;             // N per row
  int view_resolution = 32;  // G: the u(v) map is G x G
  int rays = 1024;           // hemisphere rays per vertex
  bool shadowed = true;
  std::uint64_t seed = 1;
  int effort = fit::kDefaultEffort;
  fit::NormalSource normals = fit::NormalSource::automatic;
  UpAxis up = UpAxis::y;  // an OBJ's up axis (a glTF is +Y up); the table records it
  int threads = 0;
};

struct GlossyReport {
  std::size_t vertices = 0;
  // Normalised RMS over vertices and view samples, relative to sum ||B T||_F^2:
  // svd = the SVD's truncation alone, zh = what the ZH fit of the rows adds, total = both
  // (the two are orthogonal: the SVD's error is outside U~'s columns, the fit's inside).
  double svd_nrms = 0, zh_nrms = 0, total_nrms = 0;
  double rows_nrms = 0;  // the fit's normalised RMS against the rows M' themselves
  std::vector<double> singular_values;
  double brdf_seconds = 0, simulate_seconds = 0, fit_seconds = 0;
};

// Throws InputError naming the option when a value is out of range or an output cannot
// be written.
void check_request(const GlossyRequest& request);

// Checks, runs, writes the table and the summary (both or neither).
GlossyReport run_fit_glossy(const GlossyRequest& request);

}  // namespace shtool::glossy
