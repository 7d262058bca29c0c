// Generated scenes by name, wherever a scene is taken (trace, rays, check,
// render, hard, bench, the Python API): gen:KIND:N, for the generators of
// host/scene/generate.h and gen:subdiv-MESH:N, a mesh of
// ../shared/scenes/meshes/ beside the source tree subdivided to N triangles.
#pragma once

#include <string>
#include <string_view>

#include "host/scene/scene.h"

namespace cr {

// True for names of the form gen:... (LoadScene then generates them).
bool IsGeneratedName(std::string_view name);

// The kinds, as "a|b|c" for help texts and messages.
std::string GeneratedKinds();

// Checks gen:KIND:N (InputError naming what is wrong) and returns its short
// name, "KIND-N", for tables and file names.
std::string GeneratedShortName(const std::string& name);

// Generates the scene gen:KIND:N names (InputError for a bad name).
Scene LoadGenerated(const std::string& name);

// The source tree (the directory holding scenes/spd and bench/), searched
// from the working directory and from the executable's location; empty when
// neither leads to it.
std::string FindSourceRoot();

// ../shared/scenes/meshes beside the source tree `root` ("" for no root).
std::string MeshDir(const std::string& root);

// ../shared/scenes/meshes/NAME.obj beside the source tree, or "" when absent.
std::string MeshPath(const std::string& name);

}  // namespace cr
