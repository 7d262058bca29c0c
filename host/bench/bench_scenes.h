// Scenes for `cellray bench`: names resolved to files (SPD scenes shipped in
// scenes/spd/, the real meshes of ../shared/scenes/meshes/ beside the source
// tree when present) or to generated scenes, and the default list.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "host/scene/scene.h"

namespace cr::bench {

struct SceneRef {
  std::string name;   // short name used in tables and file names
  std::string path;   // file, or "gen:KIND:N" for a generated scene
  std::string shown;  // path as recorded: relative to the source tree when inside or beside it
  bool generated = false;
};

// The source tree (the directory holding scenes/spd and bench/), searched
// from the working directory and from the executable's location; empty when
// neither leads to it.
std::string FindSourceRoot();

// ../shared/scenes/meshes/NAME.obj beside the source tree, or "" when absent.
std::string MeshPath(const std::string& name);

// The generated scene kinds (gen:KIND:N), as "a|b|c" for help and messages.
std::string GeneratedKinds();

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
