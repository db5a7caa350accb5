#include <iomanip>
#include <iostream>

#include "inhand/app/commands.hpp"
#include "inhand/core/error.hpp"
#include "inhand/sessions/simulator.hpp"

namespace inhand::app {

SimulateOptions SimulateOptionsOf(const SimulateCommand& cmd) {
  if (cmd.scenario.empty())
    throw InputError("simulate: give a SCENARIO (see inhand simulate --list)");
  if (cmd.out.empty()) throw InputError("simulate: --out DIR is required");
  SimulateOptions options;
  options.scenario = cmd.scenario;
  options.out_dir = cmd.out;
  options.seed = cmd.seed;
  options.noise = ParseNoiseProfile(cmd.noise);
  options.overwrite = cmd.overwrite;
  options.images = !cmd.no_images;
  if (!cmd.effects.empty() || !cmd.without.empty()) {
    Effects e = cmd.effects.empty() ? EffectsOf(options) : Effects::Parse(cmd.effects, "--effects");
    if (!cmd.without.empty()) e = e.Without(Effects::Parse(cmd.without, "--without"));
    options.effects = e;
  }
  return options;
}

int RunSimulate(const SimulateCommand& cmd) {
  if (cmd.list) {
    for (const ScenarioInfo& s : ListScenarios())
      std::cout << std::left << std::setw(22) << s.name << std::right << std::setw(5) << std::fixed
                << std::setprecision(1) << s.duration << " s  " << s.description << "\n";
    return 0;
  }
  const SimulateOptions options = SimulateOptionsOf(cmd);
  const SimulationSummary s = Simulate(options);
  std::cout << std::fixed << std::setprecision(3) << "session " << s.session_dir << ": "
            << s.duration << " s simulated in " << s.wall_time << " s (" << s.wall_time / s.duration
            << "x real time), " << s.joint_samples << " joint samples, " << s.camera_frames
            << " camera frames\n"
            << std::setprecision(2) << "max penetration " << s.max_penetration * 1000
            << " mm, held " << 100 * s.held_fraction
            << " % of the time after the grasp, in-hand rotation " << s.tilt_in_hand_deg
            << " deg at the end (max " << s.max_in_hand_rotation_deg
            << "), travel before the grasp " << s.table_travel_before_grasp * 1000 << " mm, lifted "
            << s.lift_height * 1000 << " mm\n";
  if (const Effects effects = EffectsOf(options); effects.Any()) {
    std::cout << "realism effects:";
    for (const std::string& n : effects.Names()) std::cout << " " << n;
    std::cout << "\n";
  }
  return 0;
}

}  // namespace inhand::app
