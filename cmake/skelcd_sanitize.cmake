# make sanitize: Debug, ASan + UBSan, asserts on, for every target.
if(SKELCD_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
