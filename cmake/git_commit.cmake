# Build-time script (cmake -P): writes the git commit of the source tree (with "-dirty" when
# tracked files differ from it) into OUT, rewriting the file only when the commit changed, so
# that every build records the commit it was built from (a configure-time value goes stale
# after the next commit) without recompiling anything when nothing changed.
execute_process(COMMAND git rev-parse HEAD WORKING_DIRECTORY "${SRC}"
  OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT commit)
  set(commit "unknown")
else()
  execute_process(COMMAND git status --porcelain --untracked-files=no WORKING_DIRECTORY "${SRC}"
    OUTPUT_VARIABLE dirty OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(dirty)
    set(commit "${commit}-dirty")
  endif()
endif()
set(text "// Generated at build time by cmake/git_commit.cmake.\n#include \"lsmbs/core/version.hpp\"\nconst char* lsmbs::git_commit() { return \"${commit}\"; }\n")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
endif()
if(NOT "${old}" STREQUAL "${text}")
  file(WRITE "${OUT}" "${text}")
endif()
