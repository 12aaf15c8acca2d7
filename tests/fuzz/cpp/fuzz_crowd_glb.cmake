# fuzz_crowd_glb links the crowd benchmark's loader (bench/crowd/lod_asset.cpp, morph_weights.cpp,
# animation_pointers.cpp) with Debian's tinygltf and nlohmann's JSON, like animlod_crowd itself:
# only in a top-level build with the crowd on and both installed. The core library never links
# them.
find_package(TinyGLTF CONFIG QUIET)
find_package(nlohmann_json 3 CONFIG QUIET)
if(NOT (ANIMLOD_BUILD_CROWD AND PROJECT_IS_TOP_LEVEL) OR NOT TARGET TinyGLTF::TinyGLTF
   OR NOT TARGET nlohmann_json::nlohmann_json)
  message(STATUS "fuzz_crowd_glb: off (needs the crowd benchmark's libtinygltf-dev and nlohmann-json3-dev)")
  set(harness_enabled OFF)
  return()
endif()
list(APPEND harness_sources "${PROJECT_SOURCE_DIR}/bench/crowd/lod_asset.cpp"
            "${PROJECT_SOURCE_DIR}/bench/crowd/morph_weights.cpp"
            "${PROJECT_SOURCE_DIR}/bench/crowd/animation_pointers.cpp")
list(APPEND harness_libraries TinyGLTF::TinyGLTF nlohmann_json::nlohmann_json)
list(APPEND harness_include_dirs "${PROJECT_SOURCE_DIR}/bench/crowd")
