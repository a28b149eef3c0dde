# Install rules: `cmake --install BUILD [--prefix DIR]` puts in place
#   bin/softgi                         the program
#   lib/libsoftgi.a                    the library: softgi_api (the API) and softgi_core in one archive
#   include/softgi/softgi.h            its one public header
#   lib/pkgconfig/softgi.pc            for `pkg-config --cflags --libs --static softgi`
#   share/doc/softgi/api.md, examples/render_frame.c
# (lib is CMAKE_INSTALL_LIBDIR: lib/x86_64-linux-gnu under /usr on Debian.)
# Included at the end of the top-level CMakeLists.txt, after the targets.
#
# Static, not shared: softgi_core is built without -fPIC and exports every
# pf_/rs_/gi_ symbol; a shared libsoftgi.so would need position-independent
# code in every target (the program's too) and a symbol list keeping the
# internals hidden, and the API's structs are not yet an ABI promise
# (version 0.x). Every dependency is itself a shared library on Debian, so
# a static libsoftgi.a costs a user nothing but the Requires.private and
# Libs.private below, which `pkg-config --static` prints.
include(GNUInstallDirs)

# libsoftgi.a: softgi_api's and softgi_core's members in one archive (an ar
# MRI script: every member is kept, also the same kernel file compiled once
# per ISA, which `ar x` would overwrite), so a program links one library
# whatever softgi_core is assembled from.
set(SOFTGI_ARCHIVE ${CMAKE_BINARY_DIR}/libsoftgi.a)
file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/softgi_archive.mri CONTENT
     "CREATE ${SOFTGI_ARCHIVE}\nADDLIB $<TARGET_FILE:softgi_api>\nADDLIB $<TARGET_FILE:softgi_core>\nSAVE\nEND\n")
add_custom_command(
  OUTPUT ${SOFTGI_ARCHIVE}
  COMMAND ${CMAKE_COMMAND} -E rm -f ${SOFTGI_ARCHIVE}
  COMMAND ${CMAKE_AR} -M < ${CMAKE_BINARY_DIR}/softgi_archive.mri
  DEPENDS softgi_api softgi_core ${CMAKE_BINARY_DIR}/softgi_archive.mri
  COMMENT "Archiving libsoftgi.a (softgi_api + softgi_core)")
add_custom_target(softgi_archive ALL DEPENDS ${SOFTGI_ARCHIVE})

install(TARGETS softgi RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES ${SOFTGI_ARCHIVE} DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(FILES include/softgi/softgi.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/softgi)
install(FILES docs/api.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(FILES examples/render_frame.c examples/CMakeLists.txt DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples)

# softgi.pc. Relocatable: the prefix is found from the file's own place
# (${pcfiledir}), so `cmake --install --prefix DIR` needs no reconfigure.
# What a static link of libsoftgi.a needs: the libraries softgi_core links
# (CMakeLists.txt) that have a .pc file go to Requires.private, the others
# (Embree, meshoptimizer, tinyexr: CMake packages only) to Libs.private, with
# the C++ runtime (pf_gltf.cpp, pf_exr.cpp) and the threads. GLFW and OpenGL
# are left out: only the viewer's window (pf_window.c) uses them, and no
# function of the API reaches it, so its object is never linked.
# The fuzz build compiles tinygltf and tinyexr into the library instead; it
# is not meant to be installed.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(SOFTGI_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
  set(SOFTGI_PC_LIBDIR "${CMAKE_INSTALL_FULL_LIBDIR}")
  set(SOFTGI_PC_INCLUDEDIR "${CMAKE_INSTALL_FULL_INCLUDEDIR}")
else()
  file(RELATIVE_PATH SOFTGI_PC_UP "/softgi-prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/softgi-prefix")
  string(REGEX REPLACE "/$" "" SOFTGI_PC_UP "${SOFTGI_PC_UP}")
  set(SOFTGI_PC_PREFIX "\${pcfiledir}/${SOFTGI_PC_UP}")
  set(SOFTGI_PC_LIBDIR "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
  set(SOFTGI_PC_INCLUDEDIR "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
endif()
file(CONFIGURE OUTPUT ${CMAKE_BINARY_DIR}/softgi.pc CONTENT [=[
prefix=@SOFTGI_PC_PREFIX@
libdir=@SOFTGI_PC_LIBDIR@
includedir=@SOFTGI_PC_INCLUDEDIR@

Name: softgi
Description: pure-CPU software-rasterizing renderer with VPL global illumination (C API)
Version: @PROJECT_VERSION@
Requires.private: tinygltf stb libcjson spng libturbojpeg
Cflags: -I${includedir}
Libs: -L${libdir} -lsoftgi
Libs.private: -lembree3 -lmeshoptimizer -ltinyexr -lstdc++ -lm -pthread
]=] @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/softgi.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
