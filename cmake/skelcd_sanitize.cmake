# make sanitize: Debug, ASan + UBSan, asserts on, for every target.
if(SKELCD_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()

# Leaks inside system libraries that keep process-lifetime caches are suppressed by name
# (cmake/lsan.supp); every test (and every skelcd it starts) sees the file through LSAN_OPTIONS.
set(SKELCD_TEST_ENVIRONMENT "")
if(SKELCD_SANITIZE)
  set(SKELCD_TEST_ENVIRONMENT
      "LSAN_OPTIONS=suppressions=${PROJECT_SOURCE_DIR}/cmake/lsan.supp:print_suppressions=0")
endif()
