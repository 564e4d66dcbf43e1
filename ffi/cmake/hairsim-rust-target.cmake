# hairsim_rust_target(TARGET RUSTFLAGS): the Rust target and flags for the C toolchain in use
# (HAIRSIM_RUST_TARGET if set). A native build is the host's (empty target). An ARM cross
# toolchain is a Cortex-M4F: thumbv7em-none-eabihf with -mfloat-abi=hard, else
# thumbv7em-none-eabi for the Cortex-M4's FPU with the soft-float calling convention
# (-mfloat-abi=softfp: `-C target-cpu=cortex-m4` gives it the FPU).
function(hairsim_rust_target out_target out_rustflags)
  set(target "${HAIRSIM_RUST_TARGET}")
  set(flags "")
  string(TOLOWER "${CMAKE_SYSTEM_PROCESSOR}" processor)
  set(c_flags "${CMAKE_C_FLAGS} ${CMAKE_C_FLAGS_INIT}")
  if(NOT target AND CMAKE_CROSSCOMPILING AND processor MATCHES "^(arm|thumb|cortex)")
    if(c_flags MATCHES "-mfloat-abi=hard")
      set(target thumbv7em-none-eabihf)
    elseif(c_flags MATCHES "-mfloat-abi=softfp")
      set(target thumbv7em-none-eabi)
    else()
      message(FATAL_ERROR "hairsim: an ARM toolchain without -mfloat-abi=hard or softfp: "
                          "set HAIRSIM_RUST_TARGET (the core needs a Cortex-M4F's FPU)")
    endif()
  elseif(NOT target AND CMAKE_CROSSCOMPILING)
    message(FATAL_ERROR "hairsim: set HAIRSIM_RUST_TARGET for ${CMAKE_SYSTEM_PROCESSOR}")
  endif()
  if(target STREQUAL "thumbv7em-none-eabi")
    set(flags "-C target-cpu=cortex-m4")
  endif()
  set(${out_target} "${target}" PARENT_SCOPE)
  set(${out_rustflags} "${flags}" PARENT_SCOPE)
endfunction()
