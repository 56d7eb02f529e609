// The mesh as an Embree scene, for the rays of the transfer simulation and of the
// renderer: one triangle geometry, robust (watertight) traversal, high build quality.
#pragma once

#include <limits>
#include <memory>
#include <string>

#include <embree3/rtcore.h>

#include "fit/mesh.h"

namespace shtool::fit {

// Embree picks its kernels from the CPU, and its AVX2 and AVX-512 kernels can report
// different hits for the same ray, so a bake would depend on the machine it ran on.
// Every device is capped at SSE4.2 (`max_isa=`), which every x86-64 CPU of the last
// fifteen years has: shards and ranks on mixed hardware then run the same kernels.
inline constexpr const char* kEmbreeMaxIsa = "sse4.2";

// What a table records of the ray tracer, so that parts made by different kernels are
// never merged: the Embree library version ("3.13.5") and the ISA its kernels run
// here ("sse4.2", or "sse2" on a CPU without SSE4.2).
struct EmbreeIdentity {
  std::string version;
  std::string isa;
};
EmbreeIdentity embree_identity();

// An unbounded ray (tnear 0, every mask bit) from origin along dir, in Embree's floats.
inline RTCRay embree_ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
  RTCRay ray{};
  ray.org_x = static_cast<float>(origin.x());
  ray.org_y = static_cast<float>(origin.y());
  ray.org_z = static_cast<float>(origin.z());
  ray.dir_x = static_cast<float>(dir.x());
  ray.dir_y = static_cast<float>(dir.y());
  ray.dir_z = static_cast<float>(dir.z());
  ray.tnear = 0.0f;
  ray.tfar = std::numeric_limits<float>::infinity();
  ray.mask = 0xFFFFFFFFu;
  ray.time = 0.0f;
  return ray;
}

// A mesh in Embree's floats. A mesh far from the origin for its size (a level's prop, a
// georeferenced scan) is stored about its box's centre: at 1e4 units float's spacing
// (1e-3) is coarser than the rays' offset off the surface and shadows break. Rays are
// made with ray(), which moves their origin alike (distances and directions are
// unchanged); a mesh near the origin is stored as it is (center zero).
struct EmbreeScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  ~EmbreeScene() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  RTCRay ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const {
    return embree_ray(origin - center, dir);
  }
};

// A device with the pinned ISA. Throws std::runtime_error if Embree refuses it.
RTCDevice new_pinned_device();

// Throws std::runtime_error if Embree cannot create the device or build the scene.
std::unique_ptr<EmbreeScene> build_scene(const Mesh& mesh);

}  // namespace shtool::fit
