// The mesh as an Embree scene, for the rays of the transfer simulation and of the
// renderer: one triangle geometry, robust (watertight) traversal, high build quality.
#pragma once

#include <memory>

#include <embree3/rtcore.h>

#include "fit/mesh.h"

namespace shtool::fit {

struct EmbreeScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~EmbreeScene() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

// Throws std::runtime_error if Embree cannot create the device or build the scene.
std::unique_ptr<EmbreeScene> build_scene(const Mesh& mesh);

}  // namespace shtool::fit
