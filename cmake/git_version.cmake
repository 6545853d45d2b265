# Writes OUTPUT (a C++ fragment for geometry/version.cpp) with the project
# version and `git describe --always --dirty` of SOURCE_DIR, or an empty
# describe where the source is not a git checkout or git is missing. Run at
# every build (cmake -P); the file is rewritten only when its text changes,
# so an unchanged tree recompiles nothing.
set(describe "")
find_package(Git QUIET)
if(GIT_FOUND)
  # Only the source's own checkout: not a repository that merely contains it.
  execute_process(COMMAND ${GIT_EXECUTABLE} -C ${SOURCE_DIR} rev-parse --show-toplevel
                  OUTPUT_VARIABLE top RESULT_VARIABLE rc ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(rc EQUAL 0)
    file(REAL_PATH "${top}" top)
    file(REAL_PATH "${SOURCE_DIR}" source)
  endif()
  if(rc EQUAL 0 AND top STREQUAL source)
    execute_process(COMMAND ${GIT_EXECUTABLE} -C ${SOURCE_DIR} describe --always --dirty
                    OUTPUT_VARIABLE out RESULT_VARIABLE rc ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
    if(rc EQUAL 0)
      set(describe "${out}")
    endif()
  endif()
endif()
set(text "#define VOX_PROJECT_VERSION \"${PROJECT_VERSION}\"\n#define VOX_GIT_DESCRIBE \"${describe}\"\n")
set(old "")
if(EXISTS ${OUTPUT})
  file(READ ${OUTPUT} old)
endif()
if(NOT old STREQUAL text)
  file(WRITE ${OUTPUT} "${text}")
endif()
