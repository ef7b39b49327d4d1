# CPack pre-build script (CPACK_PRE_BUILD_SCRIPTS, HapticdPackage.cmake): splits the debug
# information off every ELF file of the staged install, the way dh_strip does. Each file keeps
# its code, loses its debug sections and gains a .gnu_debuglink; the sections go to
# usr/lib/debug/.build-id/NN/REST.debug, packed as hapticd-dbgsym_VERSION_ARCH.ddeb
# (Package-Type: ddeb, Depends: hapticd (= VERSION)) beside the package.
find_program(OBJCOPY objcopy REQUIRED)
find_program(READELF readelf REQUIRED)
find_program(DPKG_DEB dpkg-deb REQUIRED)

set(staged "${CPACK_TEMPORARY_DIRECTORY}")
set(debug_root "${CPACK_TOPLEVEL_DIRECTORY}/dbgsym")
file(REMOVE_RECURSE "${debug_root}")
file(GLOB_RECURSE candidates LIST_DIRECTORIES false "${staged}/*")
set(build_ids "")
foreach(file IN LISTS candidates)
    if(IS_SYMLINK "${file}")
        continue()
    endif()
    execute_process(COMMAND "${READELF}" --notes "${file}" OUTPUT_VARIABLE notes
                    ERROR_QUIET RESULT_VARIABLE not_elf)
    if(NOT not_elf EQUAL 0 OR NOT notes MATCHES "Build ID: ([0-9a-f][0-9a-f])([0-9a-f]+)")
        continue()  # not an ELF file with a build ID: a config, a page, a script
    endif()
    set(id_dir "${debug_root}/usr/lib/debug/.build-id/${CMAKE_MATCH_1}")
    set(debug_file "${id_dir}/${CMAKE_MATCH_2}.debug")
    list(APPEND build_ids "${CMAKE_MATCH_1}${CMAKE_MATCH_2}")
    file(MAKE_DIRECTORY "${id_dir}")
    execute_process(COMMAND "${OBJCOPY}" --only-keep-debug --compress-debug-sections "${file}"
                            "${debug_file}" COMMAND_ERROR_IS_FATAL ANY)
    execute_process(COMMAND "${OBJCOPY}" --strip-debug --strip-unneeded
                            "--add-gnu-debuglink=${debug_file}" "${file}"
                    COMMAND_ERROR_IS_FATAL ANY)
endforeach()
if(NOT build_ids)
    message(FATAL_ERROR "HapticdSplitDebug: no ELF file with a build ID in ${staged}")
endif()

execute_process(COMMAND dpkg --print-architecture OUTPUT_VARIABLE arch
                OUTPUT_STRIP_TRAILING_WHITESPACE COMMAND_ERROR_IS_FATAL ANY)
set(version "${CPACK_PACKAGE_VERSION}")
list(JOIN build_ids " " build_id_field)
file(MAKE_DIRECTORY "${debug_root}/DEBIAN")
file(WRITE "${debug_root}/DEBIAN/control"
"Package: hapticd-dbgsym
Package-Type: ddeb
Source: hapticd
Version: ${version}
Architecture: ${arch}
Maintainer: ${CPACK_PACKAGE_CONTACT}
Depends: hapticd (= ${version})
Section: debug
Priority: optional
Auto-Built-Package: debug-symbols
Build-Ids: ${build_id_field}
Description: debug symbols for hapticd
")
set(ddeb "${CPACK_PACKAGE_DIRECTORY}/hapticd-dbgsym_${version}_${arch}.ddeb")
# The sections are compressed already (--compress-debug-sections): xz would take a minute
# for little.
execute_process(COMMAND "${DPKG_DEB}" --root-owner-group -Znone --build "${debug_root}" "${ddeb}"
                OUTPUT_QUIET COMMAND_ERROR_IS_FATAL ANY)
message(STATUS "HapticdSplitDebug: ${ddeb}")
