# Warnings and sanitizers applied to every Weft target through weft_target_defaults().
add_library(weft_warnings INTERFACE)
target_compile_options(weft_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual -Wnull-dereference -Wdouble-promotion
    -Wimplicit-fallthrough
    # Designated initialisers that leave defaulted members out are the intended way to fill *Desc
    # structs (as with Box2D defs); GCC 12 warns about them under -Wextra.
    -Wno-missing-field-initializers>)
if(WEFT_WERROR)
  target_compile_options(weft_warnings INTERFACE $<$<COMPILE_LANGUAGE:CXX>:-Werror>)
endif()
# Bit-reproducible floating point: no fused multiply-add contraction behind our back (Box2D does the
# same), so the CPU backend gives the same bits on every machine and thread count.
target_compile_options(weft_warnings INTERFACE $<$<COMPILE_LANGUAGE:CXX>:-ffp-contract=off>)
if(WEFT_SANITIZE)
  target_compile_options(weft_warnings INTERFACE -fsanitize=${WEFT_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  target_link_options(weft_warnings INTERFACE -fsanitize=${WEFT_SANITIZE})
endif()

# Build-only: the installed static libraries must not ask their users for Weft's warning flags.
function(weft_target_defaults target)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:weft_warnings>)
endfunction()
