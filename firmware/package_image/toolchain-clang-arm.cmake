# clang for the STM32F417 (Cortex-M4F): compiled by clang --target=thumbv7em-none-eabihf with the CPU
# flags of firmware/flags.py ARM_CPU (what armclang, Keil MDK 6, is built on); linked by
# arm-none-eabi-gcc, whose libgcc and linker the image uses (Debian's clang 14 comes without lld).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER clang)
set(CMAKE_C_COMPILER_TARGET thumbv7em-none-eabihf)
set(CMAKE_AR arm-none-eabi-ar CACHE FILEPATH "")
set(CMAKE_RANLIB arm-none-eabi-ranlib CACHE FILEPATH "")
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(CMAKE_C_FLAGS_INIT "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
# The link step without the compile flags (clang's --target means nothing to arm-none-eabi-gcc).
set(CMAKE_C_LINK_EXECUTABLE "arm-none-eabi-gcc <LINK_FLAGS> <OBJECTS> -o <TARGET> <LINK_LIBRARIES>")
