# Finds the core's dependencies from system packages; nothing is downloaded.
# A missing package stops the configure step with the Debian package to install.

# OpenMesh: prefer the release build made by scripts/build_release_openmesh.sh (Debian's
# libopenmesh-dev has assertions compiled in, 5-7x slower collapses; see third_party_notes.md).
# OpenMesh's config has no version file, so no version is asked for.
set(ANIMLOD_OPENMESH_PREFIX "${PROJECT_SOURCE_DIR}/.deps/openmesh"
    CACHE PATH "Prefix of a release OpenMesh build, preferred over the system package")
find_package(OpenMesh CONFIG QUIET PATHS "${ANIMLOD_OPENMESH_PREFIX}" NO_DEFAULT_PATH)
if(OpenMesh_FOUND)
  set(ANIMLOD_OPENMESH_SOURCE "release build in ${ANIMLOD_OPENMESH_PREFIX}")
else()
  find_package(OpenMesh CONFIG QUIET)
  if(NOT OpenMesh_FOUND)
    message(FATAL_ERROR "animlod needs OpenMesh: run scripts/build_release_openmesh.sh .deps/openmesh "
                        "(or 'make setup'), or install the Debian package libopenmesh-dev")
  endif()
  set(ANIMLOD_OPENMESH_SOURCE "system package (${OpenMesh_DIR})")
  message(WARNING "animlod: using the system OpenMesh, which Debian builds with assertions on: "
                  "edge collapses run 5-7x slower. 'make setup' builds a release OpenMesh.")
endif()
message(STATUS "animlod: OpenMesh from ${ANIMLOD_OPENMESH_SOURCE}")

find_package(Eigen3 3.3 CONFIG QUIET)
if(NOT TARGET Eigen3::Eigen)
  message(FATAL_ERROR "animlod needs Eigen 3.3+: install the Debian package libeigen3-dev")
endif()

find_package(glm CONFIG QUIET)
if(NOT TARGET glm::glm)
  message(FATAL_ERROR "animlod needs GLM: install the Debian package libglm-dev")
endif()

# nlopt's C library: the per-frame SLSQP solve of the motion LoD re-fit (private to the core).
find_package(NLopt 2.7 CONFIG QUIET)
if(NOT TARGET NLopt::nlopt)
  message(FATAL_ERROR "animlod needs nlopt 2.7+ (C library, SLSQP for the motion LoD re-fit): "
                      "install the Debian package libnlopt-dev")
endif()
