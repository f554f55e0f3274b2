# mcg_warnings: the project's warning set; errors only when MCG_WERROR is on (CI, developers).
add_library(mcg_warnings INTERFACE)
target_compile_options(mcg_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast
    -Wcast-align -Woverloaded-virtual -Wconversion -Wsign-conversion
    -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough>
  $<$<COMPILE_LANGUAGE:C>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion>)
if(MCG_WERROR)
  target_compile_options(mcg_warnings INTERFACE -Werror)
endif()
