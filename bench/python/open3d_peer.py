"""Open3D, crux's Python peer, imported so that its RaycastingScene can hit anything.

Open3D < 0.19 gives Embree rays of mask 0; an Embree 3 built with ray masks (Debian's libembree3-3)
then drops every hit, and every ray query of RaycastingScene answers "no hit"
(bench/python/open3d_embree_mask.c has the cause and the evidence). `import_open3d()` loads that
file's shim, built by CMake as <build>/python/crux_open3d_embree_mask.so, into the global symbol
scope before importing Open3D when both hold:

- Open3D's distribution is older than 0.19 (0.19 sets the mask to all ones itself; its Embree 4 has
  other signatures for the functions the shim replaces), and
- the libembree3.so.3 the dynamic loader finds reports RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED.

Used by bench/python/bench_open3d.py and tests/python/test_open3d.py.
"""

import ctypes
import importlib.metadata
import os
import sys

SHIM_NAME = "crux_open3d_embree_mask.so"
RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED = 64  # embree3/rtcore_device.h


def open3d_version():
    """Open3D's version from its distribution metadata, as a tuple of ints; None if not installed."""
    try:
        text = importlib.metadata.version("open3d")
    except importlib.metadata.PackageNotFoundError:
        return None
    parts = []
    for part in text.split("+")[0].split("."):
        digits = "".join(c for c in part if c.isdigit())
        parts.append(int(digits) if digits else 0)
    return tuple(parts)


def embree3_ray_mask_supported():
    """Whether libembree3.so.3 (as the dynamic loader finds it) was built with ray masks."""
    try:
        embree = ctypes.CDLL("libembree3.so.3")
    except OSError:
        return False
    embree.rtcNewDevice.restype = ctypes.c_void_p
    embree.rtcNewDevice.argtypes = [ctypes.c_char_p]
    embree.rtcGetDeviceProperty.restype = ctypes.c_ssize_t
    embree.rtcGetDeviceProperty.argtypes = [ctypes.c_void_p, ctypes.c_int]
    embree.rtcReleaseDevice.argtypes = [ctypes.c_void_p]
    device = embree.rtcNewDevice(None)
    if not device:
        return False
    try:
        return embree.rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED) != 0
    finally:
        embree.rtcReleaseDevice(device)


def shim_path():
    """The shim: $CRUX_OPEN3D_EMBREE_MASK if set, else beside the crux package of the build tree
    (<build>/python/crux_open3d_embree_mask.so); None if there is no such file."""
    path = os.environ.get("CRUX_OPEN3D_EMBREE_MASK")
    if not path:
        import crux

        path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(crux.__file__))), SHIM_NAME)
    return path if os.path.isfile(path) else None


def import_open3d():
    """Imports Open3D, first loading the ray-mask shim when this Open3D and Embree need it.

    Returns (open3d, shim), shim one of:
      "loaded <path>"  the shim was needed and is loaded: ray queries are fixed;
      "missing"        it was needed but is not built (libembree-dev absent): ray queries hit nothing;
      "too late"       it was needed but Open3D was imported before: ray queries hit nothing;
      "not needed"     Open3D >= 0.19, or an Embree without ray masks.
    Raises ImportError when Open3D is not importable."""
    version = open3d_version()
    if version is None or version >= (0, 19) or not embree3_ray_mask_supported():
        shim = "not needed"
    elif "open3d" in sys.modules:
        shim = "too late"
    else:
        path = shim_path()
        if path is None:
            shim = "missing"
        else:
            ctypes.CDLL(path, mode=os.RTLD_NOW | os.RTLD_GLOBAL)
            shim = "loaded " + path
    import open3d

    return open3d, shim
