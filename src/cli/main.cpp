// main.cpp: the hbil command line. The only place that turns errors into exit codes.
#include <OpenImageIO/imageio.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "cli/commands.h"
#include "hbil/error.h"

int main(int argc, char** argv) {
  CLI::App app{"hbil " HBIL_VERSION
               ": screen-space ambient occlusion, bent cones and indirect light (HBIL) for "
               "rendered OpenEXR G-buffer sequences"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "hbil " HBIL_VERSION);
  hbil::cli::add_run(app);
  hbil::cli::add_farm(app);
  hbil::cli::add_bench(app);
  hbil::cli::add_tune(app);
  hbil::cli::add_info(app);
  hbil::cli::add_compare(app);
  hbil::cli::add_preset(app);
  hbil::cli::add_import_povray(app);
  // Every --help names the manual and the exit codes.
  const std::string footer =
      "\nExit codes: 0 done, 1 internal error, 2 usage, 3 input missing or unreadable, 4 "
      "pass missing, 5 bad data, 6 no usable camera, 7 preset, 8 output cannot be written, 9 "
      "farm check found frames not done.\n"
      "Manual (every option, layer and exit code): man hbil, or man -l man/hbil.1 in the "
      "source tree.";
  app.footer(footer);
  for (CLI::App* sub : app.get_subcommands({})) {
    sub->footer(footer);
    for (CLI::App* subsub : sub->get_subcommands({})) subsub->footer(footer);
  }
  // OIIO's own thread pool is not needed: hbil parallelises with TBB.
  // OIIO::attribute("threads", 1);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return int(hbil::Exit::usage);
  } catch (const hbil::Error& e) {
    std::cerr << "hbil: error: " << e.what() << "\n";
    return int(e.code());
  } catch (const std::exception& e) {
    std::cerr << "hbil: internal error: " << e.what() << "\n";
    return int(hbil::Exit::failure);
  }
  return 0;
}
