#include "fit/embree_scene.h"

#include <stdexcept>
#include <string>

namespace shtool::fit {

RTCDevice new_pinned_device() {
  const std::string config = std::string("max_isa=") + kEmbreeMaxIsa;
  RTCDevice device = rtcNewDevice(config.c_str());
  if (!device) throw std::runtime_error("Embree: cannot create a device with '" + config + "'");
  return device;
}

EmbreeIdentity embree_identity() {
  RTCDevice device = new_pinned_device();
  const long v = static_cast<long>(rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_VERSION));
  rtcReleaseDevice(device);
  EmbreeIdentity id;
  id.version = std::to_string(v / 10000) + "." + std::to_string(v / 100 % 100) + "." + std::to_string(v % 100);
  // Embree 3 does not report the ISA it chose; below the cap it takes the best the CPU
  // has, and its SSE4.2 kernels need SSSE3, SSE4.1, SSE4.2 and POPCNT.
  const bool sse42 = __builtin_cpu_supports("ssse3") && __builtin_cpu_supports("sse4.1") &&
                     __builtin_cpu_supports("sse4.2") && __builtin_cpu_supports("popcnt");
  id.isa = sse42 ? kEmbreeMaxIsa : "sse2";
  return id;
}

std::unique_ptr<EmbreeScene> build_scene(const Mesh& mesh) {
  auto s = std::make_unique<EmbreeScene>();
  s->device = new_pinned_device();
  s->scene = rtcNewScene(s->device);
  // Robust mode: watertight traversal, so rays grazing a shared edge cannot leak.
  rtcSetSceneFlags(s->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(s->scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geom = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), mesh.positions.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(unsigned), mesh.triangles.size()));
  if (!vb || !ib) {
    rtcReleaseGeometry(geom);
    throw std::runtime_error("Embree: cannot allocate geometry buffers");
  }
  if (!mesh.positions.empty()) {
    Eigen::Vector3d lo = mesh.positions[0], hi = lo;
    for (const Eigen::Vector3d& p : mesh.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    const Eigen::Vector3d mid = 0.5 * (lo + hi);
    if (mid.cwiseAbs().maxCoeff() > (hi - lo).maxCoeff()) s->center = mid;
  }
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    for (int c = 0; c < 3; ++c) vb[3 * i + c] = static_cast<float>(mesh.positions[i][c] - s->center[c]);
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int c = 0; c < 3; ++c) ib[3 * i + c] = static_cast<unsigned>(mesh.triangles[i][c]);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(s->scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(s->scene);
  if (rtcGetDeviceError(s->device) != RTC_ERROR_NONE) throw std::runtime_error("Embree: scene build failed");
  return s;
}

}  // namespace shtool::fit
