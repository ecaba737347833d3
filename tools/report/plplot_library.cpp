#include "tools/report/plplot_library.hpp"

#include <dlfcn.h>

#include <string>
#include <type_traits>

#include "skinning/errors.hpp"

#ifndef SKELCD_PLPLOT_SONAME
#error "SKELCD_PLPLOT_SONAME (its soname) comes with the skelcd_plplot_headers target"
#endif

namespace skelcd::tools::detail {

PlplotLibrary open_plplot_library(const std::string& soname) {
  // RTLD_LOCAL: its symbols stay out of the process's scope (nothing else looks them up there).
  void* handle = ::dlopen(soname.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = ::dlerror();
    throw IoError(
        "plotting needs PLplot (Debian: libplplot17 and plplot-driver-cairo): " +
        (why != nullptr ? std::string(why) : soname + " cannot be opened"));
  }
  PlplotLibrary out;
  std::string missing;
  const auto find = [&](const char* symbol, auto& slot) {
    slot = reinterpret_cast<std::remove_reference_t<decltype(slot)>>(::dlsym(handle, symbol));
    if (slot == nullptr) missing += std::string(missing.empty() ? "" : ", ") + symbol;
  };
#define SKELCD_PLPLOT_FIND(name) find("c_" #name, out.name);
  SKELCD_PLPLOT_FUNCTIONS(SKELCD_PLPLOT_FIND)
#undef SKELCD_PLPLOT_FIND
  if (!missing.empty()) {
    ::dlclose(handle);
    throw IoError("plotting needs PLplot: " + soname + " lacks " + missing);
  }
  return out;  // the handle stays open: the table points into it
}

const PlplotLibrary& plplot() {
  // The table, or the reason it could not be filled: opened once, the same answer after.
  struct Loaded {
    PlplotLibrary library;
    std::string error;
  };
  static const Loaded loaded = [] {
    Loaded l;
    try {
      l.library = open_plplot_library(SKELCD_PLPLOT_SONAME);
    } catch (const IoError& e) {
      l.error = e.what();
    }
    return l;
  }();
  if (!loaded.error.empty()) throw IoError(loaded.error);
  return loaded.library;
}

}  // namespace skelcd::tools::detail
