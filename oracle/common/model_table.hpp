#pragma once
/// @file model_table.hpp  Model bookkeeping shared by the peer backends (exact, fcl, bullet):
/// names, meshes, parent links and local/world transforms, so that every peer implements the
/// hierarchy semantics of the batch protocol in one place and only has to place its own
/// geometry at the world poses this table computes.
///
/// The hierarchy itself is crux::ModelHierarchy (flat arrays, no recursion, cycle check, remove
/// keeps the children's world pose). World transforms are composed there in crux::Real with
/// quarter-turn rotations snapped (model_query.hpp); a peer that needs its own exact
/// composition (the CGAL backend) walks parent()/local() itself.

#include <crux/model/hierarchy.hpp>
#include <crux/world/collision_world.hpp>

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace crux::oracle {

/// Names -> models of one world, over a ModelHierarchy. Errors are crux::InvalidInput naming
/// the protocol field ("name", "model", "parent").
class ModelTable {
 public:
  /// Adds a model named `name` (non-empty, not in use) of `mesh` (whose crux mesh is `data`),
  /// placed by `local` relative to `parent` (none: the world).
  ModelHandle add(const std::string& name, MeshHandle mesh, std::shared_ptr<const Mesh> data, const Transform& local,
                  std::optional<ModelHandle> parent);
  /// Removes a model; its children move to its parent keeping their world pose. Returns the
  /// children that moved (their local transforms changed, their world poses did not).
  std::vector<ModelHandle> remove(ModelHandle model);
  /// Sets the local transform. Returns the model and its descendants (their world poses changed).
  std::vector<ModelHandle> setLocal(ModelHandle model, const Transform& local);
  /// Re-parents keeping the world pose (none: detach). A cycle throws InvalidInput("parent: ...").
  void setParent(ModelHandle model, std::optional<ModelHandle> parent);

  std::optional<ModelHandle> find(std::string_view name) const;
  bool contains(ModelHandle model) const;
  const std::string& name(ModelHandle model) const;
  MeshHandle mesh(ModelHandle model) const;
  const std::shared_ptr<const Mesh>& meshData(ModelHandle model) const;
  const Transform& local(ModelHandle model) const;
  std::optional<ModelHandle> parent(ModelHandle model) const;
  /// world = parent_world ∘ local (crux::Real, quarter turns exact).
  const Transform& world(ModelHandle model) const;
  /// The names of every descendant, sorted.
  std::vector<std::string> descendantNames(ModelHandle model) const;
  /// The descendants' handles (any order).
  std::vector<ModelHandle> descendants(ModelHandle model) const;
  /// Live models, ascending handles.
  std::vector<ModelHandle> models() const;
  std::size_t size() const { return hierarchy_.size(); }

 private:
  ModelId require(ModelHandle model, const char* field) const;

  ModelHierarchy hierarchy_;
  std::vector<std::string> names_;  // by ModelId; empty for free ids
  std::vector<MeshHandle> meshes_;  // by ModelId
  std::map<std::string, ModelId, std::less<>> byName_;
};

}  // namespace crux::oracle
