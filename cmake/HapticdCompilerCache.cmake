# The compiler cache (ccache, a Debian package that scripts/install-deps installs): every
# compile of C and C++ goes through it when it is on PATH and HAPTICD_CCACHE is ON (the default).
# CI builds the release, asan and tsan trees in a fresh clone of a commit this machine has
# usually just built; the cache turns those builds' compiles into lookups.
#
# A clone's path must not change what is cached: CCACHE_BASEDIR makes the paths under the
# source tree relative before ccache hashes the command line, CCACHE_NOHASHDIR leaves the
# working directory out of the hash, and -ffile-prefix-map writes the source tree as "." into
# the objects' debug info and __FILE__, so an object is the same whichever clone compiled it
# (and so the cached one is right for every clone). A compile whose definitions name an
# absolute path (a test's HAPTICD_SOURCE_DIR) still hashes that path, and misses in a new clone.
find_program(HAPTICD_CCACHE_PROGRAM ccache)
option(HAPTICD_CCACHE "Compile through ccache when it is installed" ON)
if(HAPTICD_CCACHE AND HAPTICD_CCACHE_PROGRAM)
  set(hapticd_compiler_launcher
      /usr/bin/env CCACHE_BASEDIR=${PROJECT_SOURCE_DIR} CCACHE_NOHASHDIR=true
      ${HAPTICD_CCACHE_PROGRAM})
  foreach(language C CXX)
    if(NOT DEFINED CMAKE_${language}_COMPILER_LAUNCHER)
      set(CMAKE_${language}_COMPILER_LAUNCHER ${hapticd_compiler_launcher})
    endif()
  endforeach()
  add_compile_options(-ffile-prefix-map=${PROJECT_SOURCE_DIR}/=)
  message(STATUS "hapticd: compiling through ${HAPTICD_CCACHE_PROGRAM}")
endif()
