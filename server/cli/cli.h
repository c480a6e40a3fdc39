#pragma once
// The `voxd` command line: inspect, voxelize (and serve, in the service).
namespace voxd::cli {

int run(int argc, char** argv);
int inspect_command(int argc, char** argv);
int voxelize_command(int argc, char** argv);
int submit_command(int argc, char** argv);
int analyze_command(int argc, char** argv);
int serve_command(int argc, char** argv);
int devices_command(int argc, char** argv);

}  // namespace voxd::cli
