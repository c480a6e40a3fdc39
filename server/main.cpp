#include "server/cli/cli.h"

int main(int argc, char** argv) { return voxd::cli::run(argc, argv); }
