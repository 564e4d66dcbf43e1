# A CMake toolchain for a Cortex-M4F with Debian's gcc-arm-none-eabi:
#   cmake -DCMAKE_TOOLCHAIN_FILE=ffi/cmake/arm-none-eabi-cortex-m4f.cmake [-DHAIRSIM_FLOAT_ABI=softfp]
# HAIRSIM_FLOAT_ABI is `hard` (floats in FPU registers; the library for thumbv7em-none-eabihf)
# or `softfp` (the FPU, floats passed in integer registers; thumbv7em-none-eabi for a
# Cortex-M4): the same hashes either way.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(HAIRSIM_FLOAT_ABI hard CACHE STRING "hard or softfp")
set(CMAKE_C_FLAGS_INIT
    "-mcpu=cortex-m4 -mthumb -mfloat-abi=${HAIRSIM_FLOAT_ABI} -mfpu=fpv4-sp-d16")
set(CMAKE_EXE_LINKER_FLAGS_INIT "--specs=nano.specs")
