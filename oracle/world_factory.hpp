#pragma once
/// @file world_factory.hpp  Collision worlds by backend name (target crux::oracle).

#include <crux/world/collision_world.hpp>

#include <memory>
#include <string_view>
#include <vector>

namespace crux {

/// Every backend name the protocol knows, in a fixed order: native, fcl, bullet, exact.
const std::vector<std::string_view>& knownBackends();
/// The backends compiled into this build (native always; the others when CMake found their
/// packages: CGAL for exact, FCL for fcl, Bullet for bullet), in knownBackends() order.
const std::vector<std::string_view>& builtBackends();
/// A fresh world answered by `backend`. Throws InvalidInput naming the backend when it is
/// unknown or not built, listing the built ones.
std::unique_ptr<CollisionWorld> makeWorld(std::string_view backend);

}  // namespace crux
