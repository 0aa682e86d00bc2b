/// @file hierarchy.cpp  ModelHierarchy: flat arrays, free list, intrusive sibling lists, world
/// transforms updated eagerly on mutation (so const members never write and are thread-safe) and
/// the moved set, all walked with loops (no recursion).
///
/// Subtree walks are pre-order traversals that follow first-child / next-sibling links and
/// climb back through parent links, so they need no stack at any depth.

#include <crux/model/hierarchy.hpp>

#include "rigid.hpp"

#include <algorithm>

namespace crux {
namespace {

std::string idText(ModelId id) { return id == kNoModel ? std::string("kNoModel") : std::to_string(id); }

/// Pre-order walk of the subtree of `root` (root included). `visit(id)` returns whether to
/// descend into id's children.
template <class FirstChild, class NextSibling, class Parent, class Visit>
void walkSubtree(ModelId root, const FirstChild& firstChild, const NextSibling& nextSibling, const Parent& parent,
                 Visit&& visit) {
  ModelId node = root;
  bool descend = visit(node);
  for (;;) {
    if (descend && firstChild(node) != kNoModel) {
      node = firstChild(node);
    } else {
      while (node != root && nextSibling(node) == kNoModel) node = parent(node);
      if (node == root) return;
      node = nextSibling(node);
    }
    descend = visit(node);
  }
}

}  // namespace

void ModelHierarchy::require(ModelId id, const char* what) const {
  if (id >= alive_.size() || !alive_[id])
    throw InvalidInput(std::string(what) + ": model " + idText(id) + " does not exist");
}

bool ModelHierarchy::contains(ModelId id) const { return id < alive_.size() && alive_[id]; }

void ModelHierarchy::link(ModelId id, ModelId parent) {
  parent_[id] = parent;
  prevSibling_[id] = kNoModel;
  nextSibling_[id] = kNoModel;
  if (parent == kNoModel) return;
  const ModelId first = firstChild_[parent];
  nextSibling_[id] = first;
  if (first != kNoModel) prevSibling_[first] = id;
  firstChild_[parent] = id;
}

void ModelHierarchy::unlink(ModelId id) {
  const ModelId p = parent_[id], prev = prevSibling_[id], next = nextSibling_[id];
  if (prev != kNoModel) nextSibling_[prev] = next;
  else if (p != kNoModel) firstChild_[p] = next;
  if (next != kNoModel) prevSibling_[next] = prev;
  parent_[id] = prevSibling_[id] = nextSibling_[id] = kNoModel;
}

bool ModelHierarchy::isAncestorOrSelf(ModelId ancestor, ModelId id) const {
  for (ModelId a = id; a != kNoModel; a = parent_[a])
    if (a == ancestor) return true;
  return false;
}

ModelId ModelHierarchy::add(std::shared_ptr<const Mesh> mesh, const Transform& local, ModelId parent) {
  if (!mesh) throw InvalidInput("add: the mesh is null");
  if (parent != kNoModel) require(parent, "add (parent)");
  validate(local, "add: local");
  ModelId id;
  if (!free_.empty()) {
    id = free_.back();
    free_.pop_back();
  } else {
    if (alive_.size() >= kNoModel) throw InvalidInput("add: too many models");
    id = ModelId(alive_.size());
    mesh_.emplace_back();
    local_.emplace_back();
    world_.emplace_back();
    parent_.push_back(kNoModel);
    firstChild_.push_back(kNoModel);
    nextSibling_.push_back(kNoModel);
    prevSibling_.push_back(kNoModel);
    moved_.push_back(0);
    alive_.push_back(0);
    generation_.push_back(0);
  }
  mesh_[id] = std::move(mesh);
  local_[id] = {model_detail::canonicalRotation(local.rotation), local.translation};
  firstChild_[id] = kNoModel;
  link(id, parent);
  alive_[id] = 1;
  moved_[id] = 0;
  world_[id] = parent == kNoModel ? local_[id] : model_detail::compose(world_[parent], local_[id]);
  ++size_;
  return id;
}

void ModelHierarchy::remove(ModelId id) {
  require(id, "remove");
  const ModelId p = parent_[id];
  const Transform* parentWorld = p == kNoModel ? nullptr : &world_[p];
  // Re-parent the children, keeping their world transforms (the stored values, unchanged).
  while (firstChild_[id] != kNoModel) {
    const ModelId c = firstChild_[id];
    unlink(c);
    link(c, p);
    local_[c] = parentWorld ? model_detail::relative(*parentWorld, world_[c]) : world_[c];
  }
  unlink(id);
  mesh_[id].reset();
  alive_[id] = 0;
  moved_[id] = 0;
  ++generation_[id];
  free_.push_back(id);
  --size_;
}

void ModelHierarchy::markMovedAndUpdateWorld(ModelId root) {
  // Pre-order: a parent's world transform is recomputed before its children's.
  walkSubtree(
      root, [&](ModelId i) { return firstChild_[i]; }, [&](ModelId i) { return nextSibling_[i]; },
      [&](ModelId i) { return parent_[i]; },
      [&](ModelId i) {
        const ModelId p = parent_[i];
        world_[i] = p == kNoModel ? local_[i] : model_detail::compose(world_[p], local_[i]);
        if (!moved_[i]) {
          moved_[i] = 1;
          movedList_.push_back(i);
        }
        return true;
      });
}

void ModelHierarchy::setLocal(ModelId id, const Transform& local) {
  require(id, "setLocal");
  validate(local, "setLocal: local");
  local_[id] = {model_detail::canonicalRotation(local.rotation), local.translation};
  markMovedAndUpdateWorld(id);
}

void ModelHierarchy::setParent(ModelId id, ModelId parent) {
  require(id, "setParent");
  if (parent != kNoModel) {
    require(parent, "setParent (parent)");
    if (isAncestorOrSelf(id, parent))
      throw InvalidInput("setParent: model " + idText(parent) + (parent == id ? " is model " : " is a descendant of model ") +
                         idText(id) + ": making it the parent would create a cycle");
  }
  if (parent_[id] == parent) return;
  unlink(id);
  link(id, parent);
  // The world transform (and the descendants') stays as stored; only the local one changes.
  local_[id] = parent == kNoModel ? world_[id] : model_detail::relative(world_[parent], world_[id]);
}

const Transform& ModelHierarchy::local(ModelId id) const {
  require(id, "local");
  return local_[id];
}

ModelId ModelHierarchy::parent(ModelId id) const {
  require(id, "parent");
  return parent_[id];
}

const std::shared_ptr<const Mesh>& ModelHierarchy::mesh(ModelId id) const {
  require(id, "mesh");
  return mesh_[id];
}

std::uint32_t ModelHierarchy::generation(ModelId id) const {
  if (id >= generation_.size()) throw InvalidInput("generation: model " + idText(id) + " was never created");
  return generation_[id];
}

const Transform& ModelHierarchy::world(ModelId id) const {
  require(id, "world");
  return world_[id];
}

PlacedMesh ModelHierarchy::placed(ModelId id) const {
  require(id, "placed");
  return {mesh_[id].get(), world_[id]};
}

std::vector<ModelId> ModelHierarchy::descendants(ModelId id) const {
  require(id, "descendants");
  std::vector<ModelId> out;
  walkSubtree(
      id, [&](ModelId i) { return firstChild_[i]; }, [&](ModelId i) { return nextSibling_[i]; },
      [&](ModelId i) { return parent_[i]; },
      [&](ModelId i) {
        if (i != id) out.push_back(i);
        return true;
      });
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<ModelId> ModelHierarchy::children(ModelId id) const {
  require(id, "children");
  std::vector<ModelId> out;
  for (ModelId c = firstChild_[id]; c != kNoModel; c = nextSibling_[c]) out.push_back(c);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<ModelId> ModelHierarchy::ids() const {
  std::vector<ModelId> out;
  out.reserve(size_);
  for (ModelId id = 0; id < alive_.size(); ++id)
    if (alive_[id]) out.push_back(id);
  return out;
}

std::vector<ModelId> ModelHierarchy::takeMoved() {
  std::vector<ModelId> out;
  out.reserve(movedList_.size());
  for (const ModelId id : movedList_) {
    if (!moved_[id]) continue;  // removed, or listed twice
    moved_[id] = 0;
    if (alive_[id]) out.push_back(id);
  }
  movedList_.clear();
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace crux
