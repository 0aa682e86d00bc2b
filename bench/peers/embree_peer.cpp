#include "embree_peer.hpp"

#include <embree3/rtcore.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace crux::bench {

namespace {

// Embree calls this from inside its API functions; record the first error, check it after.
void recordError(void* user, RTCError code, const char* message) {
  auto& first = *static_cast<std::string*>(user);
  if (first.empty()) first = "embree error " + std::to_string(int(code)) + ": " + (message ? message : "");
}

bool countBytes(void* user, ssize_t bytes, bool /*post*/) {
  static_cast<std::atomic<long long>*>(user)->fetch_add(bytes, std::memory_order_relaxed);
  return true;
}

}  // namespace

std::string EmbreeConfig::label() const {
  std::string s = robust ? "robust" : "default";
  s += highQuality ? ",high" : ",medium";
  if (threads != 1) s += threads == 0 ? ",all threads" : "," + std::to_string(threads) + " threads";
  if (refit) s = std::string(robust ? "robust" : "default") + ",dynamic,refit geometry";
  if (!maxIsa.empty()) s += ",max_isa=" + maxIsa;
  return s;
}

struct EmbreePeer::Impl {
  const MeshArrays* mesh = nullptr;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::atomic<long long> deviceBytes{0};
  std::string error;
  long long sceneBytes = 0;
};

EmbreePeer::EmbreePeer(const MeshArrays& mesh, const EmbreeConfig& config)
    : impl_(std::make_unique<Impl>()), config_(config) {
  impl_->mesh = &mesh;
  std::string cfg = config.threads > 0 ? "threads=" + std::to_string(config.threads) : std::string();
  if (!config.maxIsa.empty()) cfg += (cfg.empty() ? "" : ",") + std::string("max_isa=") + config.maxIsa;
  impl_->device = rtcNewDevice(cfg.empty() ? nullptr : cfg.c_str());
  if (!impl_->device) throw std::runtime_error("embree: rtcNewDevice failed");
  rtcSetDeviceErrorFunction(impl_->device, recordError, &impl_->error);
  rtcSetDeviceMemoryMonitorFunction(impl_->device, countBytes, &impl_->deviceBytes);
  rebuild();
}

EmbreePeer::~EmbreePeer() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

Seconds EmbreePeer::rebuild() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  impl_->scene = nullptr;
  const long long before = impl_->deviceBytes.load();
  const MeshArrays& m = *impl_->mesh;
  const RTCBuildQuality quality = config_.highQuality ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;

  const Stopwatch watch;
  RTCScene scene = rtcNewScene(impl_->device);
  // A refit scene also needs RTC_SCENE_FLAG_DYNAMIC: without it Embree 3.13.5 rebuilds the
  // REFIT geometry on every commit (measured: the same time as a MEDIUM build).
  rtcSetSceneFlags(scene, RTCSceneFlags((config_.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE) |
                                        (config_.refit ? RTC_SCENE_FLAG_DYNAMIC : RTC_SCENE_FLAG_NONE)));
  rtcSetSceneBuildQuality(scene, config_.refit ? RTC_BUILD_QUALITY_LOW : quality);
  RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geom, config_.refit ? RTC_BUILD_QUALITY_REFIT : quality);
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, m.positions.data(), 0,
                             3 * sizeof(float), m.vertexCount());
  rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m.indices.data(), 0,
                             3 * sizeof(std::uint32_t), m.triangleCount());
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  const Seconds elapsed = watch.elapsed();

  impl_->scene = scene;
  if (!impl_->error.empty()) throw std::runtime_error(impl_->error);
  impl_->sceneBytes = impl_->deviceBytes.load() - before;
  return elapsed;
}

void EmbreePeer::closestHits(const RayQuery* rays, std::size_t n, RayAnswer* out) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (std::size_t i = 0; i < n; ++i) {
    const RayQuery& q = rays[i];
    RTCRayHit rh;
    rh.ray.org_x = q.origin[0];
    rh.ray.org_y = q.origin[1];
    rh.ray.org_z = q.origin[2];
    rh.ray.tnear = 0.0f;
    rh.ray.dir_x = q.dir[0];
    rh.ray.dir_y = q.dir[1];
    rh.ray.dir_z = q.dir[2];
    rh.ray.time = 0.0f;
    rh.ray.tfar = std::numeric_limits<float>::infinity();
    rh.ray.mask = 0xffffffffu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &context, &rh);
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      // Embree's tfar is in units of |dir|; the bench's dirs are unit up to float rounding.
      const double len = std::sqrt(double(q.dir[0]) * q.dir[0] + double(q.dir[1]) * q.dir[1] +
                                   double(q.dir[2]) * q.dir[2]);
      out[i] = {float(rh.ray.tfar * len), rh.hit.primID, 1};
    } else {
      out[i] = {0.0f, kNoTriangle, 0};
    }
  }
}

namespace {

RTCRay occlusionRay(const float* origin, const float* dir, float tfar) {
  RTCRay r;
  r.org_x = origin[0];
  r.org_y = origin[1];
  r.org_z = origin[2];
  r.tnear = 0.0f;
  r.dir_x = dir[0];
  r.dir_y = dir[1];
  r.dir_z = dir[2];
  r.time = 0.0f;
  r.tfar = tfar;
  r.mask = 0xffffffffu;
  r.id = 0;
  r.flags = 0;
  return r;
}

}  // namespace

void EmbreePeer::anyHits(const RayQuery* rays, std::size_t n, std::uint8_t* out) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (std::size_t i = 0; i < n; ++i) {
    RTCRay r = occlusionRay(rays[i].origin, rays[i].dir, std::numeric_limits<float>::infinity());
    rtcOccluded1(impl_->scene, &context, &r);
    out[i] = r.tfar < 0;  // Embree sets tfar to -inf when the ray is occluded
  }
}

void EmbreePeer::segmentHits(const SegmentQuery* segments, std::size_t n, std::uint8_t* out) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (std::size_t i = 0; i < n; ++i) {
    const SegmentQuery& q = segments[i];
    const float dir[3] = {q.end[0] - q.start[0], q.end[1] - q.start[1], q.end[2] - q.start[2]};
    RTCRay r = occlusionRay(q.start, dir, 1.0f);
    rtcOccluded1(impl_->scene, &context, &r);
    out[i] = r.tfar < 0;
  }
}

Seconds EmbreePeer::refit() {
  const Stopwatch watch;
  RTCGeometry geom = rtcGetGeometry(impl_->scene, 0);
  rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(geom);
  rtcCommitScene(impl_->scene);
  const Seconds elapsed = watch.elapsed();
  if (!impl_->error.empty()) throw std::runtime_error(impl_->error);
  return elapsed;
}

std::size_t EmbreePeer::sceneBytes() const {
  return impl_->sceneBytes > 0 ? std::size_t(impl_->sceneBytes) : 0;
}

bool EmbreePeer::backfaceCulling() const {
  return rtcGetDeviceProperty(impl_->device, RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED) != 0;
}

std::string embreeVersion() { return RTC_VERSION_STRING; }

}  // namespace crux::bench
