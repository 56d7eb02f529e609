// shtool bake-probes: irradiance probe volumes baked from a glTF or OBJ scene (docs/probes.md).
#include <iostream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "probes/bake_probes_job.h"

namespace shtool::cli {

void setup_bake_probes(CLI::App* sub) {
  auto req = std::make_shared<probes::BakeProbesRequest>();
  sub->add_option("scene", req->scene, "glTF 2.0 (.gltf/.glb) or OBJ scene")->required();
  add_up_option(sub, req->up);
  sub->add_option("--grid", req->grid, "probes along x, y, z: NX,NY,NZ")->required();
  sub->add_option("--bounds", req->bounds, "the grid's box X0,Y0,Z0,X1,Y1,Z1 in shtool's frame (default: the scene's)");
  sub->add_option("--env", req->env, "distant environment: a radiance lighting JSON (project-env, light)");
  sub->add_option("--order", req->order, "SH order N (1..8)")->capture_default_str();
  sub->add_option("--samples", req->samples, "directions per probe")->capture_default_str();
  sub->add_option("--bounces", req->bounces, "surface reflections per path (0: direct light and emitters only)")
      ->capture_default_str();
  add_seed_option(sub, req->seed, "seed of the directions and paths");
  add_threads_option(sub, req->threads);
  sub->add_option("--encoding", req->encoding,
                  "what each probe stores: l2 (the order-N coefficients), l1 (bands 0 and 1, non-linear L1 "
                  "reconstruction; --order >= 2) or zh3 (bands 0 and 1 and a zonal band-2 coefficient, --zh3-fit, --zh3-axis; "
                  "--order >= 3 for the explicit fit)")
      ->capture_default_str();
  sub->add_option("--zh3-fit", req->zh3_fit,
                  "zh3: explicit (default; the zonal coefficient fitted to band 2 and stored) or hallucinated "
                  "(nothing stored beyond L1; the reader derives the coefficient from it; --order >= 2)");
  sub->add_option("--zh3-axis", req->zh3_axis,
                  "zh3: luminance (default; one axis from the luminance-weighted L1 band) or per-channel");
  sub->add_option("--out", req->out, "probe-grid table to write")->required();
  sub->add_option("--json", req->json, "also the probes as JSON");
  sub->add_option("--threejs", req->threejs,
                  "also DIR/probes.json and DIR/probes.bin for three.js's LightProbeGridWebGL (web/shtool-three.js)");
  sub->add_option("--shard", req->shard, "bake shard K of N (0-based) of the probes into a partial table; join "
                                         "the parts with shtool merge");
  sub->add_flag("--mpi", req->mpi, "under mpirun: ranks split the probes, rank 0 writes the outputs");
  sub->callback([req]() {
    const probes::BakeProbesReport r = probes::run_bake_probes(*req);
    if (r.mpi_rank != 0) return;  // rank 0 reports the job
    if (r.unsupported_lights)
      std::cerr << "bake-probes: warning: " << r.unsupported_lights
                << " KHR_lights_punctual light(s) of a type other than directional, point or spot left out\n";
    if (r.sharded) std::cerr << "bake-probes: shard of probes [" << r.first_probe << ", " << r.end_probe << ")\n";
    std::cerr << "bake-probes: " << r.probes << " probes (" << r.resolution[0] << " x " << r.resolution[1] << " x "
              << r.resolution[2] << ", encoding " << r.encoding << "), " << r.triangles << " triangles, " << r.lights
              << " lights; " << r.rays << " rays in " << r.seconds << " s; " << r.invalid
              << (r.sharded ? " invalid probes (stored unfilled: merge fills them)"
                            : " invalid probes filled from neighbours");
    if (r.mpi_ranks) std::cerr << " (this rank's share; on each of " << r.mpi_ranks << " MPI ranks)";
    if (r.unfilled) std::cerr << " (" << r.unfilled << " with no valid neighbour left at 0)";
    std::cerr << "\nwrote " << req->out.string();
    if (!req->json.empty()) std::cerr << ", " << req->json.string();
    if (!req->threejs.empty()) std::cerr << ", " << (req->threejs / "probes.json").string() << ", probes.bin";
    std::cerr << "\n";
  });
}

}  // namespace shtool::cli
