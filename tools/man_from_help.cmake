# man_from_help.cmake: clvr.1 from `clvr --help` where help2man is not installed
# (tools/setup-debian.sh test installs it; this keeps `cmake --install` working
# on a machine set up with the run group only). A plain page: NAME, SYNOPSIS and
# the help text verbatim.
# Usage: cmake -DCLVR=path/to/clvr -DOUT=clvr.1 -DVERSION=x.y.z -P man_from_help.cmake
execute_process(COMMAND ${CLVR} --help OUTPUT_VARIABLE help RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${CLVR} --help failed (${rc})")
endif()
# roff: a backslash is written \e; a line starting with . or ' needs \& before it.
string(REPLACE "\\" "\\e" help "${help}")
string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" help "${help}")
string(TIMESTAMP month "%B %Y" UTC)
file(WRITE ${OUT}.tmp
  ".TH CLVR 1 \"${month}\" \"clvr ${VERSION}\" \"User Commands\"\n"
  ".SH NAME\nclvr \\- OpenCL path tracer for unstructured volume meshes\n"
  ".SH DESCRIPTION\n.nf\n${help}.fi\n")
file(RENAME ${OUT}.tmp ${OUT})
