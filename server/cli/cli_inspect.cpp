#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

#include "api/inside_choice.h"
#include "api/result_json.h"
#include "server/cli/cli.h"
#include "server/cli/cli_args.h"
#include "server/mapped_file.h"
#include "voxd/mesh_io/mesh_decode.h"
#include "voxd/edge_topology.h"
#include "voxd/mesh_orientation.h"
#include "voxd/mesh_report.h"

namespace voxd::cli {

int inspect_command(int argc, char** argv) {
  Args args(argc, argv, 2, {}, {"help"});
  if (args.has("help")) {
    std::cout << "usage: voxd inspect MESH\n\nPrints the mesh report (topology, bounds, area, volume) of the file as it is, as\n"
                 "JSON, with what a job would do to it: \"orientation\", the triangles and parts orienting\n"
                 "it turns round (inverted_components: parts written inside out), and \"inside\", the\n"
                 "inside test \"inside\": \"auto\" chooses for it.\n";
    return 0;
  }
  if (args.positional().size() != 1) throw UsageError("inspect takes exactly one mesh file");
  const std::string& path = args.positional()[0];
  MappedFile file(path);
  DecodeWarnings warnings;
  const Mesh mesh = decode_mesh(file.bytes(), path, {}, &warnings);
  MeshReport report = make_mesh_report(mesh);
  report.warnings = std::move(warnings);
  Mesh oriented = mesh;
  const OrientationRepair repair = orient_outward(oriented);
  report.orientation = repair;
  nlohmann::json out = api::to_json(report);
  const EdgeTopology topology = count_edge_topology(mesh);
  out["inside"] = api::to_json(api::choose_inside_test(api::JobParams(), &topology));
  out["format"] = to_string(detect_mesh_format(file.bytes(), path));
  std::cout << out.dump(2) << '\n';
  return 0;
}

}  // namespace voxd::cli
