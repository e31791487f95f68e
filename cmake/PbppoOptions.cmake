# Project-wide compile settings: target architecture, sanitizers, warning sets.

if(PBPPO_ARCH AND CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64")
  add_compile_options(-march=${PBPPO_ARCH})
endif()

if(PBPPO_SANITIZE)
  add_compile_options(-fsanitize=${PBPPO_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${PBPPO_SANITIZE})
  add_compile_definitions(PBPPO_SANITIZED=1)
endif()

# Fuzzing builds instrument every target for coverage; fuzz executables add the libFuzzer driver.
if(PBPPO_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "PBPPO_FUZZ needs clang (use the 'fuzz' preset)")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()

# Strict warnings, errors on the real-time code (runtime/).
function(pbppo_strict_warnings target)
  target_compile_options(${target} PRIVATE
    -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Wshadow -Wdouble-promotion
    -Wold-style-cast -Wcast-align -Wnull-dereference -Wformat=2 -Wimplicit-fallthrough
    -Wnon-virtual-dtor -Woverloaded-virtual -Werror)
endfunction()

# Ordinary warnings for tools, tests and trainer code.
function(pbppo_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wshadow)
endfunction()
