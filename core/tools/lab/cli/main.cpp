// glimpse-lab: offline tools over the core library and the lab library. Each subcommand lives in its own
// file of cli/ and registers itself here.
#include <CLI/CLI.hpp>

namespace glimpse::lab {
void add_eval_command(CLI::App& app);   // eval.cpp
void add_views_command(CLI::App& app);  // views.cpp
void add_compare_command(CLI::App& app);  // compare.cpp
void add_scenes_command(CLI::App& app);   // scenes.cpp
}  // namespace glimpse::lab

int main(int argc, char** argv) {
  CLI::App app{"glimpse-lab: offline tools for Glimpse (evaluation protocol, single views, comparing runs, scenes)"};
  app.require_subcommand(1);
  glimpse::lab::add_eval_command(app);
  glimpse::lab::add_views_command(app);
  glimpse::lab::add_compare_command(app);
  glimpse::lab::add_scenes_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {  // a subcommand failed; it printed why
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return 0;
}
