# kdrt_set_warnings(target): -Wall -Wextra (and -Werror when asked) on our own code only.
# Also -ffp-contract=off: the watertight triangle test relies on a*b - c*d
# rounding the same way for both triangles of an edge, which fused
# multiply-adds would break (the kernels say the same with FP_CONTRACT OFF).
function(kdrt_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -ffp-contract=off)
  if(KDRT_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
