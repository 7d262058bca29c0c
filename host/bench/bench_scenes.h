// Scenes for `cellray bench`: names resolved to files (SPD scenes shipped in
// scenes/spd/, the real meshes of ../shared/scenes/meshes/ beside the source
// tree when present) or to generated scenes, and the default list.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "host/scene/generated.h"
#include "host/scene/scene.h"

namespace cr::bench {

struct SceneRef {
  std::string name;   // short name used in tables and file names
  std::string path;   // file, or "gen:KIND:N" for a generated scene
  std::string shown;  // path as recorded: relative to the source tree when inside or beside it
  bool generated = false;
};

// FindSourceRoot, MeshDir, MeshPath and GeneratedKinds live with the
// generated scenes (host/scene/generated.h), which every command loads.
using ::cr::FindSourceRoot;
using ::cr::GeneratedKinds;
using ::cr::MeshDir;
using ::cr::MeshPath;

// The 7 SPD scenes of the benchmark issue, in order.
const std::vector<std::string>& DefaultSpdScenes();

// Resolves names: an existing file; an SPD name (scenes/spd/NAME.nff); a mesh
// name (../shared/scenes/meshes/NAME.obj); or gen:sphereflake:DEPTH,
// gen:bumpy:TRIANGLES, gen:stadium:DEPTH, gen:subdiv-MESH:TRIANGLES (that
// mesh subdivided). No names: the 7 SPD scenes and,
// when the mesh directory exists, its meshes (`notes` says when it does not).
// InputError for a name that resolves to nothing.
std::vector<SceneRef> ResolveScenes(const std::vector<std::string>& names, std::vector<std::string>& notes);

// Loads a resolved scene (generating it for gen: references).
Scene LoadBenchScene(const SceneRef& ref);

}  // namespace cr::bench
