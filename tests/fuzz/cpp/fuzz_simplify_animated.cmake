# fuzz_simplify_animated checks vertex_map against the pieces the collapse engine works on, which
# it gets from the core's private mesh preparation (cpp/src/mesh_preparation.hpp).
list(APPEND harness_include_dirs "${PROJECT_SOURCE_DIR}/cpp/src")
