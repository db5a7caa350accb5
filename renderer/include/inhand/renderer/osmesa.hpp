#pragma once
// OSMesa, the software OpenGL every offscreen picture is drawn with, opened on first use rather
// than when the process starts: its LLVM backend costs 0.06 s to load, and most commands (import,
// evaluate's parent, compare, a tracker without extracted features) never render.
namespace inhand {

// The address of an OSMesa function ("OSMesa...") or of a GL function of OSMesa's contexts
// ("gl..."), loading libOSMesa on the first call (thread-safe). Cast it to the function's type
// (decltype(&::OSMesaMakeCurrent)). GL functions come from OSMesaGetProcAddress, so they reach
// OSMesa's contexts whatever other libGL the process has loaded. Throws InputError naming the
// library or the function when either is missing.
void* OsMesaFunction(const char* name);

}  // namespace inhand
