# mcg_warnings: the project's warning set; errors only when MCG_WERROR is on (CI, developers).
add_library(mcg_warnings INTERFACE)
target_compile_options(mcg_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast
    -Wcast-align -Woverloaded-virtual -Wconversion -Wsign-conversion
    -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough
    # The dual numbers' vector type (model/dual.hpp) passes by value only between functions of
    # this program; GCC's notes on how other compilers pass it do not concern it.
    -Wno-psabi>
  $<$<COMPILE_LANGUAGE:C>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion>)
# A link-time optimiser compiles again: the same note, the same reason.
target_link_options(mcg_warnings INTERFACE -Wno-psabi)
if(MCG_WERROR)
  target_compile_options(mcg_warnings INTERFACE -Werror)
endif()
