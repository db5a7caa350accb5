#include "inhand/renderer/osmesa.hpp"

#include <GL/osmesa.h>
#include <dlfcn.h>

#include <cstring>
#include <string>

#include "inhand/core/error.hpp"

namespace inhand {

namespace {

constexpr const char* kOsMesaLibrary = "libOSMesa.so.8";

struct OsMesaLibrary {
  void* handle = nullptr;
  decltype(&::OSMesaGetProcAddress) get_proc_address = nullptr;
};

OsMesaLibrary Open() {
  OsMesaLibrary lib;
  // Never closed: contexts and the function addresses handed out live as long as the process.
  lib.handle = dlopen(kOsMesaLibrary, RTLD_NOW | RTLD_LOCAL);
  if (!lib.handle) {
    const char* why = dlerror();
    throw InputError(std::string("cannot load ") + kOsMesaLibrary +
                     " (OSMesa, offscreen OpenGL) to render: " + (why ? why : "unknown error") +
                     " (scripts/install-deps.sh installs libosmesa6)");
  }
  lib.get_proc_address =
      reinterpret_cast<decltype(lib.get_proc_address)>(dlsym(lib.handle, "OSMesaGetProcAddress"));
  if (!lib.get_proc_address)
    throw InputError(std::string(kOsMesaLibrary) + " has no OSMesaGetProcAddress");
  return lib;
}

// The first call opens the library; a failure throws and the next call tries again.
const OsMesaLibrary& Library() {
  static const OsMesaLibrary lib = Open();
  return lib;
}

}  // namespace

void* OsMesaFunction(const char* name) {
  const OsMesaLibrary& lib = Library();
  void* function = std::strncmp(name, "OSMesa", 6) == 0
                       ? dlsym(lib.handle, name)
                       : reinterpret_cast<void*>(lib.get_proc_address(name));
  if (!function) throw InputError(std::string(kOsMesaLibrary) + " has no " + name);
  return function;
}

}  // namespace inhand
