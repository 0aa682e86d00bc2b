/// @file world_factory.cpp  makeWorld: the backend table of this build.

#include "world_factory.hpp"

#include <crux/world/native_world.hpp>

#if CRUX_ORACLE_HAVE_EXACT
#include "exact/exact_world.hpp"
#endif
#if CRUX_ORACLE_HAVE_FCL
#include "fcl/fcl_world.hpp"
#endif
#if CRUX_ORACLE_HAVE_BULLET
#include "bullet/bullet_world.hpp"
#endif

#include <string>

namespace crux {
namespace {

struct BackendEntry {
  std::string_view name;
  std::unique_ptr<CollisionWorld> (*make)();  ///< null when not built
};

const std::vector<BackendEntry>& backendTable() {
  static const std::vector<BackendEntry> table = {
      {"native", &makeNativeWorld},
#if CRUX_ORACLE_HAVE_FCL
      {"fcl", &fcl_oracle::makeFclWorld},
#else
      {"fcl", nullptr},
#endif
#if CRUX_ORACLE_HAVE_BULLET
      {"bullet", &bullet_oracle::makeBulletWorld},
#else
      {"bullet", nullptr},
#endif
#if CRUX_ORACLE_HAVE_EXACT
      {"exact", &exact::makeExactWorld},
#else
      {"exact", nullptr},
#endif
  };
  return table;
}

std::string joined(const std::vector<std::string_view>& names) {
  std::string out;
  for (const std::string_view n : names) out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}

}  // namespace

const std::vector<std::string_view>& knownBackends() {
  static const std::vector<std::string_view> names = [] {
    std::vector<std::string_view> out;
    for (const BackendEntry& e : backendTable()) out.push_back(e.name);
    return out;
  }();
  return names;
}

const std::vector<std::string_view>& builtBackends() {
  static const std::vector<std::string_view> names = [] {
    std::vector<std::string_view> out;
    for (const BackendEntry& e : backendTable())
      if (e.make) out.push_back(e.name);
    return out;
  }();
  return names;
}

std::unique_ptr<CollisionWorld> makeWorld(std::string_view backend) {
  for (const BackendEntry& e : backendTable()) {
    if (e.name != backend) continue;
    if (!e.make)
      throw InvalidInput("backend: \"" + std::string(backend) + "\" is not built into this crux (built: " +
                         joined(builtBackends()) + ")");
    return e.make();
  }
  throw InvalidInput("backend: unknown backend \"" + std::string(backend) + "\" (known: " + joined(knownBackends()) +
                     "; built: " + joined(builtBackends()) + ")");
}

}  // namespace crux
