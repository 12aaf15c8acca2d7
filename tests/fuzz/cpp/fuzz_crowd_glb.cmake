# fuzz_crowd_glb links the crowd benchmark's loader (bench/crowd/lod_asset.cpp) and Debian's
# tinygltf, like animlod_crowd itself: only in a top-level build with the crowd on and tinygltf
# installed. The core library never links tinygltf.
find_package(TinyGLTF CONFIG QUIET)
if(NOT (ANIMLOD_BUILD_CROWD AND PROJECT_IS_TOP_LEVEL) OR NOT TARGET TinyGLTF::TinyGLTF)
  message(STATUS "fuzz_crowd_glb: off (needs the crowd benchmark's tinygltf: libtinygltf-dev)")
  set(harness_enabled OFF)
  return()
endif()
list(APPEND harness_sources "${PROJECT_SOURCE_DIR}/bench/crowd/lod_asset.cpp")
list(APPEND harness_libraries TinyGLTF::TinyGLTF)
list(APPEND harness_include_dirs "${PROJECT_SOURCE_DIR}/bench/crowd")
