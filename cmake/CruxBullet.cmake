# Finds Bullet's collision module (BulletCollision + LinearMath) once and defines the imported
# target crux_bullet_collision (its include directory is a SYSTEM one). Debian's
# BulletConfig.cmake gives paths relative to BULLET_ROOT_DIR and no imported targets. The default
# libraries are the single-precision build (the -float64 ones would need BT_USE_DOUBLE_PRECISION).
# Used by oracle/ (the bullet backend) and bench/ (the Bullet peers).
include_guard(GLOBAL)
find_package(Bullet QUIET)
if(BULLET_FOUND)
  set(_crux_bullet_inc "")
  foreach(dir ${BULLET_INCLUDE_DIRS})
    if(NOT IS_ABSOLUTE "${dir}" AND BULLET_ROOT_DIR)
      set(dir "${BULLET_ROOT_DIR}/${dir}")
    endif()
    list(APPEND _crux_bullet_inc "${dir}")
  endforeach()
  set(_crux_bullet_libdirs "")
  foreach(dir ${BULLET_LIBRARY_DIRS})
    if(NOT IS_ABSOLUTE "${dir}" AND BULLET_ROOT_DIR)
      set(dir "${BULLET_ROOT_DIR}/${dir}")
    endif()
    list(APPEND _crux_bullet_libdirs "${dir}")
  endforeach()
  find_library(CRUX_BULLET_COLLISION_LIB NAMES BulletCollision HINTS ${_crux_bullet_libdirs})
  find_library(CRUX_BULLET_MATH_LIB NAMES LinearMath HINTS ${_crux_bullet_libdirs})
  find_path(CRUX_BULLET_INCLUDE btBulletCollisionCommon.h HINTS ${_crux_bullet_inc} PATH_SUFFIXES bullet)
  if(CRUX_BULLET_COLLISION_LIB AND CRUX_BULLET_MATH_LIB AND CRUX_BULLET_INCLUDE)
    add_library(crux_bullet_collision INTERFACE IMPORTED GLOBAL)
    set_target_properties(crux_bullet_collision PROPERTIES
      INTERFACE_INCLUDE_DIRECTORIES "${CRUX_BULLET_INCLUDE}"
      INTERFACE_LINK_LIBRARIES "${CRUX_BULLET_COLLISION_LIB};${CRUX_BULLET_MATH_LIB}")
  endif()
endif()
