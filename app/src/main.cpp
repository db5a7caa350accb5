// inhand: command-line entry. Parsing only (CLI11 is slow to compile: keep it in this file).
#include <CLI/CLI.hpp>
#include <iostream>

#include "inhand/app/commands.hpp"
#include "inhand/core/error.hpp"

int main(int argc, char** argv) {
  CLI::App cli{"inhand: in-hand object pose estimation and its visual debugger"};
  cli.require_subcommand(1);

  inhand::app::ModelCommand model;
  auto* model_cmd = cli.add_subcommand("model", "Load a hand URDF or an object description and summarise it");
  model_cmd->add_option("FILE", model.file, "hand URDF or object .json")->required();
  model_cmd->add_option("--package", model.packages, "resolve package://NAME as DIR (NAME=DIR)");
  model_cmd->add_flag("--json", model.json, "print JSON");

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (*model_cmd) return inhand::app::RunModel(model);
  } catch (const inhand::InputError& e) {
    std::cerr << "inhand: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "inhand: error: " << e.what() << "\n";
    return 2;
  }
  return 2;
}
