# skelcd::hdf5 — the HDF5 C library as skelcd links it (after find_package(HDF5 COMPONENTS C)).
#
# Executables take Debian's static archive (libhdf5-dev ships it beside the shared library):
# libhdf5.so pulls in libcurl, OpenSSL, GnuTLS, Kerberos and LDAP for its S3 driver, which skelcd
# never uses, and the dynamic loader spent half of every process start on them (`skelcd --help`:
# 56 shared libraries, 12.7 ms; with the archive 29 and 5.9 ms — the serial start of every check,
# docs/benchmarks.md "parallel"). From the archive the linker takes only the objects skelcd calls,
# which need libsz (libaec-dev, a dependency of libhdf5-dev), zlib, libdl and libm. A shared
# object (the Python extension) cannot hold the archive's non-PIC code and links libhdf5.so.
# Every target that uses HDF5 links this target, never HDF5::HDF5 directly, so that no program
# holds both copies. SKELCD_STATIC_HDF5=OFF, SKELCD_FUZZ=ON, or no archive found, links the shared
# library everywhere.
option(SKELCD_STATIC_HDF5 "Link executables with HDF5's static archive (faster process start)" ON)

add_library(skelcd_hdf5 INTERFACE)
add_library(skelcd::hdf5 ALIAS skelcd_hdf5)
target_include_directories(skelcd_hdf5 SYSTEM INTERFACE ${HDF5_C_INCLUDE_DIRS} ${HDF5_INCLUDE_DIRS})
target_compile_definitions(skelcd_hdf5 INTERFACE ${HDF5_C_DEFINITIONS} ${HDF5_DEFINITIONS})

# The fuzz build (make fuzz) keeps the shared library: its leak suppressions (fuzz/lsan.supp) and
# scripts/fuzz.sh's sorting of crashes tell libhdf5's own faults from ours by the name of its
# shared object, which a static copy inside the harness does not carry.
set(_skelcd_hdf5_archive "")
if(SKELCD_STATIC_HDF5 AND SKELCD_FUZZ)
  message(STATUS "skelcd: the fuzz build links libhdf5.so (SKELCD_STATIC_HDF5 ignored)")
elseif(SKELCD_STATIC_HDF5)
  set(_skelcd_hdf5_dirs "")
  foreach(_lib IN LISTS HDF5_C_LIBRARIES)
    if(_lib MATCHES "hdf5[^/]*\\.so$")
      get_filename_component(_dir "${_lib}" DIRECTORY)
      list(APPEND _skelcd_hdf5_dirs "${_dir}")
    endif()
  endforeach()
  find_library(SKELCD_HDF5_ARCHIVE NAMES libhdf5.a libhdf5_serial.a
               HINTS ${_skelcd_hdf5_dirs} NO_DEFAULT_PATH)
  find_library(SKELCD_SZ_LIBRARY NAMES sz)
  if(SKELCD_HDF5_ARCHIVE AND SKELCD_SZ_LIBRARY)
    set(_skelcd_hdf5_archive "${SKELCD_HDF5_ARCHIVE}")
  else()
    message(STATUS "skelcd: no static HDF5 archive (or no libsz): executables link libhdf5.so")
  endif()
endif()

if(_skelcd_hdf5_archive)
  # $<TARGET_PROPERTY:TYPE> in a link interface is the type of the target being linked.
  set(_exe "$<STREQUAL:$<TARGET_PROPERTY:TYPE>,EXECUTABLE>")
  target_link_libraries(skelcd_hdf5 INTERFACE
    "$<${_exe}:${_skelcd_hdf5_archive}>"
    "$<${_exe}:${SKELCD_SZ_LIBRARY}>"
    "$<${_exe}:ZLIB::ZLIB>"
    "$<${_exe}:${CMAKE_DL_LIBS}>"
    "$<${_exe}:m>"
    "$<$<NOT:${_exe}>:HDF5::HDF5>")
  message(STATUS "skelcd: executables link ${_skelcd_hdf5_archive}")
else()
  target_link_libraries(skelcd_hdf5 INTERFACE HDF5::HDF5)
endif()
