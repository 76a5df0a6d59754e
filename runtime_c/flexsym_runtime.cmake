# Included by every generated variant's CMakeLists.txt (see templates/CMakeLists.txt.j2).
# flexsym_add_model(NAME [SYSTEM] sources...) builds, from the generated sources plus this runtime:
#   flexsym_NAME      the command-line driver (src/driver.c)
#   libflexsym_NAME   a shared library exposing the kernels, fsr_simulate and fsr_batch (tests, Python)
# SYSTEM: the sources define fsm_system_model() (system.h); without it, a one-beam model is
# wrapped into that struct by src/model_adapter.c.
set(FLEXSYM_RUNTIME_DIR "${CMAKE_CURRENT_LIST_DIR}")
# The run loop (simulate.c), one file per integrator (integrator.h) and what they share.
set(FLEXSYM_RUNTIME_SOURCES)
foreach(f simulate.c batch.c rk4.c dopri5.c erk.c genalpha.c newmark.c radau5.c newton.c ode.c
          ali3p.c genalpha3.c rk4p.c constrained.c common.c linalg.c)
  list(APPEND FLEXSYM_RUNTIME_SOURCES "${FLEXSYM_RUNTIME_DIR}/src/${f}")
endforeach()

if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
  set(CMAKE_BUILD_TYPE Release)
endif()

# The flags of every model build: the driver, the shared library and an FMU compute the same
# rows bit for bit only when compiled alike. The runtime's loops run over a few coordinates
# (3 to 65): vector code costs more than it saves there (measured: 5-13 % faster integration
# of #1-#3 without it, ef 3 %).
set(FLEXSYM_WARNINGS -Wall -Wextra -Werror -pedantic)
set(FLEXSYM_CODEGEN $<$<C_COMPILER_ID:GNU,Clang,AppleClang>:-fno-tree-vectorize>)

# A model's sources: the given ones plus model_adapter.c (a one-beam model seen as an
# fsm_system), or, when the first is SYSTEM, the rest alone (they define fsm_system_model()).
function(_flexsym_model_sources out)
  set(sources ${ARGN})
  if(sources AND "${ARGV1}" STREQUAL "SYSTEM")
    list(REMOVE_AT sources 0)
  else()
    list(APPEND sources "${FLEXSYM_RUNTIME_DIR}/src/model_adapter.c")
  endif()
  set(${out} ${sources} PARENT_SCOPE)
endfunction()

function(flexsym_add_model name)
  set(objs flexsym_${name}_objects)
  _flexsym_model_sources(sources ${ARGN})
  add_library(${objs} OBJECT ${sources} ${FLEXSYM_RUNTIME_SOURCES})
  set_target_properties(${objs} PROPERTIES POSITION_INDEPENDENT_CODE ON C_STANDARD 99
                        C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
  target_include_directories(${objs} PUBLIC "${FLEXSYM_RUNTIME_DIR}/include"
                             "${CMAKE_CURRENT_SOURCE_DIR}")
  target_compile_options(${objs} PUBLIC ${FLEXSYM_WARNINGS})
  target_compile_options(${objs} PRIVATE ${FLEXSYM_CODEGEN})

  add_executable(flexsym_${name} "${FLEXSYM_RUNTIME_DIR}/src/driver.c")
  set_target_properties(flexsym_${name} PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON
                        C_EXTENSIONS OFF)
  target_link_libraries(flexsym_${name} PRIVATE ${objs} m)

  add_library(flexsym_${name}_shared SHARED $<TARGET_OBJECTS:${objs}>)
  set_target_properties(flexsym_${name}_shared PROPERTIES OUTPUT_NAME flexsym_${name})
  target_link_libraries(flexsym_${name}_shared PRIVATE m)
endfunction()

# flexsym_add_fmu(ID CONFIG_DIR sources...) builds ID.so, the binary of an FMI 3.0 Co-Simulation
# FMU (runtime_c/fmi3, flexsym/sim/fmu.py): the model's sources, this runtime and the fmi3 wrapper,
# compiled with the flags of flexsym_add_model (so its rows equal the driver's bit for bit);
# only the fmi3* functions are exported.
# SYSTEM after CONFIG_DIR: as for flexsym_add_model (the sources define fsm_system_model()).
function(flexsym_add_fmu id config_dir)
  _flexsym_model_sources(sources ${ARGN})
  add_library(${id} MODULE ${sources} ${FLEXSYM_RUNTIME_SOURCES} "${FLEXSYM_RUNTIME_DIR}/fmi3/fmi3_flexsym.c")
  set_target_properties(${id} PROPERTIES PREFIX "" C_STANDARD 99 C_STANDARD_REQUIRED ON
                        C_EXTENSIONS OFF C_VISIBILITY_PRESET hidden)
  target_include_directories(${id} PRIVATE "${FLEXSYM_RUNTIME_DIR}/include" "${FLEXSYM_RUNTIME_DIR}/fmi3"
                             "${config_dir}")
  target_compile_options(${id} PRIVATE ${FLEXSYM_WARNINGS} ${FLEXSYM_CODEGEN})
  target_link_libraries(${id} PRIVATE m)
endfunction()
