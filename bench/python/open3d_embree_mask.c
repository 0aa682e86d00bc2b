/* open3d_embree_mask.c: lets Open3D 0.16's RaycastingScene hit anything when its Embree 3 is built
 * with ray masks (Debian 12: python3-open3d 0.16.1+ds-2+b4 over libembree3-3 3.13.5+dfsg-2).
 *
 * The defect. Open3D 0.16.1 sets `ray.mask = 0` on every ray it hands to Embree
 * (cpp/open3d/t/geometry/RaycastingScene.cpp at v0.16.1, lines 331, 409 and 477: cast_rays,
 * test_occlusions, count_intersections; compute_occupancy and the sign of compute_signed_distance
 * count intersections too). Embree drops a hit when (geometry mask & ray mask) == 0
 * (embree v3.13.5 kernels/geometry/intersector_epilog.h, lines 40-41), but only when it was built
 * with EMBREE_RAY_MASK=ON. That option is off by default, so Open3D's wheels (Embree linked in with
 * the default) never show the bug; Debian builds libembree3 with it on
 * (rtcGetDeviceProperty(RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) is 1), and there every ray query
 * of RaycastingScene answers "no hit", even a ray straight at a single triangle.
 * compute_distance is unaffected (rtcPointQuery has no mask). Open3D 0.19.0 fixed it (commit
 * cac37c76c, "Upgrade embree to 4.3.1 (#6665)", sets the mask to -1).
 *
 * The fix. This library defines Embree 3's ray entry points rtcIntersect1M, rtcOccluded1M,
 * rtcIntersect1 and rtcOccluded1 (libOpen3D.so.0.16 imports the first two from libembree3.so.3
 * dynamically); each sets every ray's mask to all ones, which meets any non-zero geometry mask
 * (Open3D leaves Embree's default) as an Embree without ray masks would, then calls the function of the same name in libembree3.so.3. Loaded into the global
 * symbol scope before Open3D (Python: ctypes.CDLL(path, mode=os.RTLD_NOW | os.RTLD_GLOBAL) before
 * `import open3d`, or LD_PRELOAD), it is the definition libOpen3D binds to. It costs one store per
 * ray. bench/python/open3d_peer.py decides when to load it; CMake builds it into
 * <build>/python/crux_open3d_embree_mask.so when Embree 3's headers are found (python/CMakeLists.txt).
 * It is only for Open3D < 0.19: Embree 4 has other signatures for these names. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include <embree3/rtcore.h>

/** The mask of a ray that every geometry accepts. */
#define ALL_GEOMETRIES 0xFFFFFFFFu

static void (*real_intersect1M)(RTCScene, struct RTCIntersectContext*, struct RTCRayHit*, unsigned int, size_t);
static void (*real_occluded1M)(RTCScene, struct RTCIntersectContext*, struct RTCRay*, unsigned int, size_t);
static void (*real_intersect1)(RTCScene, struct RTCIntersectContext*, struct RTCRayHit*);
static void (*real_occluded1)(RTCScene, struct RTCIntersectContext*, struct RTCRay*);

/* Resolves Embree's own functions when the library is loaded, before any thread calls them (the
 * same libembree3.so.3 that libOpen3D loads later: one soname, one copy in the process). */
__attribute__((constructor)) static void resolve_embree(void) {
  void* embree = dlopen("libembree3.so.3", RTLD_NOW | RTLD_LOCAL);
  if (!embree) return; /* reported by the first call, if any */
  *(void**)&real_intersect1M = dlsym(embree, "rtcIntersect1M");
  *(void**)&real_occluded1M = dlsym(embree, "rtcOccluded1M");
  *(void**)&real_intersect1 = dlsym(embree, "rtcIntersect1");
  *(void**)&real_occluded1 = dlsym(embree, "rtcOccluded1");
}

static void require(const void* real, const char* name) {
  if (!real) {
    fprintf(stderr, "crux_open3d_embree_mask: %s not found in libembree3.so.3\n", name);
    abort();
  }
}

void rtcIntersect1M(RTCScene scene, struct RTCIntersectContext* context, struct RTCRayHit* rayhits,
                    unsigned int count, size_t stride) {
  require((const void*)real_intersect1M, "rtcIntersect1M");
  for (unsigned int i = 0; i < count; ++i) ((struct RTCRayHit*)((char*)rayhits + i * stride))->ray.mask = ALL_GEOMETRIES;
  real_intersect1M(scene, context, rayhits, count, stride);
}

void rtcOccluded1M(RTCScene scene, struct RTCIntersectContext* context, struct RTCRay* rays, unsigned int count,
                   size_t stride) {
  require((const void*)real_occluded1M, "rtcOccluded1M");
  for (unsigned int i = 0; i < count; ++i) ((struct RTCRay*)((char*)rays + i * stride))->mask = ALL_GEOMETRIES;
  real_occluded1M(scene, context, rays, count, stride);
}

void rtcIntersect1(RTCScene scene, struct RTCIntersectContext* context, struct RTCRayHit* rayhit) {
  require((const void*)real_intersect1, "rtcIntersect1");
  rayhit->ray.mask = ALL_GEOMETRIES;
  real_intersect1(scene, context, rayhit);
}

void rtcOccluded1(RTCScene scene, struct RTCIntersectContext* context, struct RTCRay* ray) {
  require((const void*)real_occluded1, "rtcOccluded1");
  ray->mask = ALL_GEOMETRIES;
  real_occluded1(scene, context, ray);
}
