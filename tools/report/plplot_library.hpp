#pragma once
// PLplot, opened on first use (dlopen) instead of linked: only `inspect --plot` and `bench --plot`
// draw, and the library with the ten it brings (its PNG driver aside) took about 1 ms of every
// start of every command (docs/benchmarks.md, "PLplot on first use"). Include this instead of
// <plplot.h>: it takes the library's types and constants from there, and replaces each function
// this module calls (plplot.h's macros plcol0 → c_plcol0, …) by one of the same name that calls
// the library's through the table plplot() filled.

#include <plplot.h>

#include <string>
#include <utility>

// The PLplot functions the plots call (to call another: add it here and #undef its macro below).
#define SKELCD_PLPLOT_FUNCTIONS(X) \
  X(pladv)                         \
  X(plbox)                         \
  X(plcol0)                        \
  X(plend1)                        \
  X(plenv)                         \
  X(plfill)                        \
  X(plgchr)                        \
  X(plgspa)                        \
  X(plinit)                        \
  X(pljoin)                        \
  X(pllab)                         \
  X(pllegend)                      \
  X(plline)                        \
  X(plmkstrm)                      \
  X(plmtex)                        \
  X(plptex)                        \
  X(plschr)                        \
  X(plscmap0n)                     \
  X(plscol0)                       \
  X(plscolbg)                      \
  X(plsdev)                        \
  X(plsfnam)                       \
  X(plspage)                       \
  X(plssub)                        \
  X(plstring)                      \
  X(plvpor)                        \
  X(plvsta)                        \
  X(plwidth)                       \
  X(plwind)

// plplot.h maps each name to the library's symbol by a macro; the names are ours from here on.
#undef pladv
#undef plbox
#undef plcol0
#undef plend1
#undef plenv
#undef plfill
#undef plgchr
#undef plgspa
#undef plinit
#undef pljoin
#undef pllab
#undef pllegend
#undef plline
#undef plmkstrm
#undef plmtex
#undef plptex
#undef plschr
#undef plscmap0n
#undef plscol0
#undef plscolbg
#undef plsdev
#undef plsfnam
#undef plspage
#undef plssub
#undef plstring
#undef plvpor
#undef plvsta
#undef plwidth
#undef plwind

namespace skelcd::tools::detail {

/// The library's functions (its symbol c_NAME for each NAME above).
struct PlplotLibrary {
#define SKELCD_PLPLOT_MEMBER(name) decltype(&::c_##name) name = nullptr;
  SKELCD_PLPLOT_FUNCTIONS(SKELCD_PLPLOT_MEMBER)
#undef SKELCD_PLPLOT_MEMBER
};

/// Opens the library `soname` (RTLD_LOCAL) and reads every function of the table from it.
/// @throws IoError "plotting needs PLplot …" with dlerror's reason, or naming the functions it
///         lacks. plplot() calls it once, with the soname of the library found at configure time.
PlplotLibrary open_plplot_library(const std::string& soname);

/// PLplot's functions, the library opened on the first call (thread-safe; never closed).
/// @throws IoError "plotting needs PLplot: …" (dlerror's reason) when it cannot be opened or
///         lacks a function; every later call throws the same.
const PlplotLibrary& plplot();

}  // namespace skelcd::tools::detail

namespace skelcd::tools {

// The calls as written against plplot.h, through the table (plplot() opens it first if needed).
#define SKELCD_PLPLOT_FORWARD(name)                            \
  template <typename... Args>                                  \
  inline auto name(Args&&... args) {                           \
    return detail::plplot().name(std::forward<Args>(args)...); \
  }
SKELCD_PLPLOT_FUNCTIONS(SKELCD_PLPLOT_FORWARD)
#undef SKELCD_PLPLOT_FORWARD

}  // namespace skelcd::tools
