# Writes OUT: #define LSQT_GIT_HASH "<commit>" of the checkout SRC ("+changes" after it when
# tracked files differ from it; "unknown" without git or outside a checkout). OUT is
# rewritten only when the text changes, so an unchanged commit rebuilds nothing.
# usage: cmake -DSRC=DIR -DOUT=FILE -P tools/git_hash.cmake
set(hash unknown)
find_program(GIT git)
if(GIT)
  execute_process(COMMAND ${GIT} -C ${SRC} rev-parse --short=12 HEAD RESULT_VARIABLE rc
                  OUTPUT_VARIABLE h OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(rc EQUAL 0 AND NOT h STREQUAL "")
    set(hash ${h})
    execute_process(COMMAND ${GIT} -C ${SRC} status --porcelain --untracked-files=no
                    OUTPUT_VARIABLE changes OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
    if(NOT changes STREQUAL "")
      string(APPEND hash "+changes")
    endif()
  endif()
endif()
set(text "#define LSQT_GIT_HASH \"${hash}\"\n")
set(old "")
if(EXISTS ${OUT})
  file(READ ${OUT} old)
endif()
if(NOT old STREQUAL text)
  file(WRITE ${OUT} "${text}")
endif()
