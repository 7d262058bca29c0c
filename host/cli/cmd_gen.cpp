// gen: procedural scenes for scaling studies.
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "host/cli/commands.h"
#include "host/core/error.h"
#include "host/scene/generate.h"

namespace cr::cli {

Run RegisterGen(CLI::App& app)
{
  struct O {
    std::string kind, out;
    int depth = 4;
    std::uint64_t triangles = 100000;
  };
  auto o = std::make_shared<O>();
  auto* cmd = app.add_subcommand("gen", "Generate a procedural scene (NFF): sphereflake, mesh or stadium");
  cmd->add_option("kind", o->kind, "sphereflake (--depth: 9^depth growth), mesh (--triangles), stadium (--depth)")
      ->required()
      ->check(CLI::IsMember({"sphereflake", "mesh", "stadium"}));
  cmd->add_option("--depth", o->depth, "Recursion depth of the sphereflake")->capture_default_str();
  cmd->add_option("--triangles", o->triangles, "Approximate triangle count of the mesh")->capture_default_str();
  cmd->add_option("-o,--output", o->out, "Output .nff file")->required();
  return [o]() {
    Scene s = o->kind == "sphereflake" ? GenerateSphereflake(o->depth)
              : o->kind == "mesh"      ? GenerateBumpySphere(o->triangles)
                                       : GenerateStadium(o->depth);
    WriteNFF(s, o->out);
    nlohmann::json j{{"kind", o->kind},
                     {"output", o->out},
                     {"primitives", s.NumPrims()},
                     {"spheres", s.spheres.size()},
                     {"triangles", s.triangles.size()}};
    std::cout << j.dump() << std::endl;
    return 0;
  };
}

}  // namespace cr::cli
