// `rtdenoise render`: placeholder until issue 3's implementation lands.
#include "commands.h"

namespace rtd::cli {

Command addRenderCommand(CLI::App& app) {
    CLI::App* c = app.add_subcommand("render", "(not implemented yet)");
    return {c, [] { return 1; }};
}

}  // namespace rtd::cli
