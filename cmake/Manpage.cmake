# qm3d(1), written at build time from the built tool's own --help and --version (the registry's
# commands and metrics, each with its summary and options): cmake/qm3d_manpage.py. The build tree
# keeps build/man/qm3d.1 (`man -l build/man/qm3d.1`); installed as share/man/man1/qm3d.1.gz,
# compressed as Debian policy wants (gzip -9n).
set(_qm3d_man_python python3)
if(EXISTS /usr/bin/python3)
  set(_qm3d_man_python /usr/bin/python3)
endif()
set(_qm3d_man_dir ${CMAKE_BINARY_DIR}/man)
add_custom_command(
  OUTPUT ${_qm3d_man_dir}/qm3d.1 ${_qm3d_man_dir}/qm3d.1.gz
  COMMAND ${CMAKE_COMMAND} -E make_directory ${_qm3d_man_dir}
  COMMAND ${CMAKE_COMMAND} -E env ASAN_OPTIONS=detect_leaks=0
          ${_qm3d_man_python} ${CMAKE_CURRENT_LIST_DIR}/qm3d_manpage.py $<TARGET_FILE:qm3d>
          ${_qm3d_man_dir}/qm3d.1 ${_qm3d_man_dir}/qm3d.1.gz
  DEPENDS qm3d ${CMAKE_CURRENT_LIST_DIR}/qm3d_manpage.py
  COMMENT "Writing the qm3d(1) manual page"
  VERBATIM)
add_custom_target(qm3d_man ALL DEPENDS ${_qm3d_man_dir}/qm3d.1 ${_qm3d_man_dir}/qm3d.1.gz)
install(FILES ${_qm3d_man_dir}/qm3d.1.gz DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
