/// @file model_table.cpp  ModelTable: names over crux::ModelHierarchy.

#include "common/model_table.hpp"

#include <crux/error.hpp>

#include <algorithm>

namespace crux::oracle {
namespace {

ModelHandle handleOf(ModelId id) { return ModelHandle{id}; }

}  // namespace

ModelId ModelTable::require(ModelHandle model, const char* field) const {
  if (!model.valid() || !hierarchy_.contains(model.index))
    throw InvalidInput(std::string(field) + ": unknown model handle " + std::to_string(model.index));
  return model.index;
}

ModelHandle ModelTable::add(const std::string& name, MeshHandle mesh, std::shared_ptr<const Mesh> data,
                            const Transform& local, std::optional<ModelHandle> parent) {
  if (name.empty()) throw InvalidInput("name: a model name must not be empty");
  if (byName_.count(name)) throw InvalidInput("name: a model named \"" + name + "\" already exists");
  const ModelId parentId = parent ? require(*parent, "parent") : kNoModel;
  const ModelId id = hierarchy_.add(std::move(data), local, parentId);
  if (id >= names_.size()) {
    names_.resize(std::size_t(id) + 1);
    meshes_.resize(std::size_t(id) + 1);
  }
  names_[id] = name;
  meshes_[id] = mesh;
  byName_.emplace(name, id);
  return handleOf(id);
}

std::vector<ModelHandle> ModelTable::remove(ModelHandle model) {
  const ModelId id = require(model, "model");
  std::vector<ModelHandle> moved;
  for (const ModelId child : hierarchy_.children(id)) moved.push_back(handleOf(child));
  hierarchy_.remove(id);
  byName_.erase(names_[id]);
  names_[id].clear();
  meshes_[id] = MeshHandle{};
  return moved;
}

std::vector<ModelHandle> ModelTable::setLocal(ModelHandle model, const Transform& local) {
  const ModelId id = require(model, "model");
  hierarchy_.setLocal(id, local);
  std::vector<ModelHandle> moved{model};
  for (const ModelId d : hierarchy_.descendants(id)) moved.push_back(handleOf(d));
  return moved;
}

void ModelTable::setParent(ModelHandle model, std::optional<ModelHandle> parent) {
  const ModelId id = require(model, "model");
  const ModelId parentId = parent ? require(*parent, "parent") : kNoModel;
  hierarchy_.setParent(id, parentId);
}

std::optional<ModelHandle> ModelTable::find(std::string_view name) const {
  const auto it = byName_.find(name);
  if (it == byName_.end()) return std::nullopt;
  return handleOf(it->second);
}

bool ModelTable::contains(ModelHandle model) const { return model.valid() && hierarchy_.contains(model.index); }

const std::string& ModelTable::name(ModelHandle model) const { return names_[require(model, "model")]; }

MeshHandle ModelTable::mesh(ModelHandle model) const { return meshes_[require(model, "model")]; }

const std::shared_ptr<const Mesh>& ModelTable::meshData(ModelHandle model) const {
  return hierarchy_.mesh(require(model, "model"));
}

const Transform& ModelTable::local(ModelHandle model) const { return hierarchy_.local(require(model, "model")); }

std::optional<ModelHandle> ModelTable::parent(ModelHandle model) const {
  const ModelId p = hierarchy_.parent(require(model, "model"));
  if (p == kNoModel) return std::nullopt;
  return handleOf(p);
}

const Transform& ModelTable::world(ModelHandle model) const { return hierarchy_.world(require(model, "model")); }

std::vector<std::string> ModelTable::descendantNames(ModelHandle model) const {
  std::vector<std::string> out;
  for (const ModelId d : hierarchy_.descendants(require(model, "model"))) out.push_back(names_[d]);
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<ModelHandle> ModelTable::descendants(ModelHandle model) const {
  std::vector<ModelHandle> out;
  for (const ModelId d : hierarchy_.descendants(require(model, "model"))) out.push_back(handleOf(d));
  return out;
}

std::vector<ModelHandle> ModelTable::models() const {
  std::vector<ModelHandle> out;
  for (const ModelId id : hierarchy_.ids()) out.push_back(handleOf(id));
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace crux::oracle
