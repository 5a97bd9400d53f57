# One interface target that carries the project's warnings and sanitizer flags; every
# first-party target links it. Generated IDL code does not (it is not ours to fix).
add_library(mrslam_warnings INTERFACE)
target_compile_options(mrslam_warnings INTERFACE -Wall -Wextra -Wpedantic -Wshadow)
if(MRSLAM_WERROR)
  target_compile_options(mrslam_warnings INTERFACE -Werror)
endif()

if(MRSLAM_SANITIZER)
  if(NOT MRSLAM_SANITIZER MATCHES "^(address|undefined|thread)$")
    message(FATAL_ERROR "MRSLAM_SANITIZER must be address, undefined or thread, not '${MRSLAM_SANITIZER}'")
  endif()
  add_compile_options(-fsanitize=${MRSLAM_SANITIZER} -fno-omit-frame-pointer)
  add_link_options(-fsanitize=${MRSLAM_SANITIZER})
endif()
