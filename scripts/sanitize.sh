#!/usr/bin/env bash
# make sanitize: AddressSanitizer with leak detection and UndefinedBehaviorSanitizer over the
# units, every parser, the fuzz targets, the filter, the tracker (threads included) and the
# importer (build-sanitize/). The long end-to-end runs (whole replays, evaluate, the GUI, the
# simulator's whole scenarios, the installed tree, the benchmarks) run once, in Release, under
# make test: under ASan they took most of CI's time and exercise the same code as the tests
# kept here.
#
#   scripts/sanitize.sh                 the split above (CI)
#   scripts/sanitize.sh --all           every test but the benchmarks and the installed tree
#   scripts/sanitize.sh -R REGEX        ctest's arguments choose among the split's tests
#
# Leaks that are Mesa's, assimp's, urdfdom's own (OSMesa leaks 480 B per context in a 10-line C
# program too) are suppressed by tests/sanitize/lsan.supp; ours are not.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD_SANITIZE:-$ROOT/build-sanitize}
ALL=0
if [ "${1:-}" = "--all" ]; then
  ALL=1
  shift
fi
# The end-to-end tests, by ctest name: whole sessions replayed or simulated through the CLI or
# the player (the Robustness tests that replay a session whole; those that feed the parsers bad
# files stay), the GUI, evaluations over many grasps or scans (Grasp.Allegro..., the YCB scans'
# distance fields), and what only checks the installed tree or runs the benchmarks. Of the
# replays and evaluations under ASan, the nine listed last took 614 of 1,530 test-seconds.
# The executables that hold nothing else (*_e2e_tests) are not built here at all; ctest lists
# each as <target>_NOT_BUILT, left out below too.
END_TO_END='^(Cli|SessionPlayer|SessionOverview|FrameComposer|Gui|Export|RoundTrip|Simulator|SimulatorPhysics|RealisticSimulation|HealthFaults)\.'
END_TO_END+='|^Robustness\.(OutputFolders|JointSamplesBeyond|AnAbsurdJointSample|TimeMisalignment|ASessionWithoutAFusable|StaleStaging|ParametersThatBreak)'
END_TO_END+='|^Grasp\.AllegroStaticGraspsAroundYcbScans$|^ContactField\.YcbScansWithTheirVhacdPieces$'
# The penetration checked against brute force (a 1 mm grid filling every link, each point looked
# up in the distance field: 125 s under ASan, most of the pass's longest test); the plausibility
# code itself stays here through HandPlausibility's other tests and the tracker's.
END_TO_END+='|^HandPlausibility\.PenetrationAgreesWithBruteForce'
END_TO_END+='|^Import\.RealAllegroBagReplaysWithA3dVideo$|^bench_smoke$|^install|^ros_node_live$|_NOT_BUILT$'
if [ $ALL -eq 1 ]; then
  GUI=ON
  TARGETS=(all)
  EXCLUDE='^bench_smoke$|^install|^Gui\.RealWindowUnderXvfb$'
else
  GUI=OFF  # no GUI test runs in the split: ImGui need not be built
  TARGETS=(inhand core_tests kinematics_tests io_tests sessions_tests contacts_tests filter_tests features_tests
           renderer_tests renderer_loading_tests simulator_tests fuzz_tests tracker_tests ros_tests app_tests)
  EXCLUDE=$END_TO_END
fi
# -O1 with line tables: half the compile time of -O2 -g (filter.cpp 103 -> 52 s), stack traces
# keep their files and lines.
cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DINHAND_SANITIZE=ON -DINHAND_BUILD_GUI=$GUI \
  -DINHAND_BUILD_PYTHON=OFF > /dev/null  # an ASan module loads only into an ASan interpreter
cmake --build "$BUILD" -j "$(nproc)" --target "${TARGETS[@]}"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1
export LSAN_OPTIONS=suppressions=$ROOT/tests/sanitize/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# The tests' sessions come from the Release simulator when it is built (make test builds it
# first): the simulator itself is tested there, and simulating a scenario under ASan cost 19 s
# instead of 6 for each of the tracker's and importer's tests that need one.
RELEASE_INHAND=${BUILD_RELEASE:-$ROOT/build}/bin/inhand
if [ $ALL -eq 0 ] && [ -x "$RELEASE_INHAND" ]; then
  export INHAND_TEST_SIMULATOR=$RELEASE_INHAND
fi
cd "$BUILD"
ctest --output-on-failure -j "$(nproc)" -E "$EXCLUDE" "$@"
# --all: the GUI in a real X window (Xvfb, GLX): Mesa's GLX path leaks 112 B in 2 blocks whose
# stacks end in libstdc++ (no frame of ours); leak detection is off for that one test only.
# Arguments (ctest's, such as -R REGEX) choose the tests above; given any, this one is left out
# (a second -R would replace its own and run the chosen tests once more).
if [ $ALL -eq 1 ] && [ $# -eq 0 ]; then
  ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 ctest --output-on-failure -R 'Gui.RealWindowUnderXvfb'
fi
