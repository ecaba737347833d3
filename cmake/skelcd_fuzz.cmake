# make fuzz: libFuzzer harnesses under fuzz/ (docs/fuzzing.md). Clang only. Every project library
# gets coverage instrumentation (fuzzer-no-link) plus ASan and UBSan; only the harnesses link the
# libFuzzer runtime (-fsanitize=fuzzer, in fuzz/CMakeLists.txt). UBSan aborts on the first report
# so libFuzzer sees it as a crash.
if(SKELCD_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "SKELCD_FUZZ needs clang (libFuzzer): configure with CC=clang-14 CXX=clang++-14")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()
