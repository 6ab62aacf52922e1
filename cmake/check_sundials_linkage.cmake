# CTest script (test "sundials_linkage"): the freeflex program contains the SUNDIALS that
# FREEFLEX_SUNDIALS chose.
#   bundled: no libsundials_* shared library is loaded, and CVode, N_VLinearSum_Serial and
#            N_VWrmsNorm_Serial in the program have the sizes they have in the bundled
#            libsundials_cvodes.a (Debian's -O0 code has other sizes: N_VLinearSum_Serial 0x47a bytes against 0x2e3);
#   system:  the program loads Debian's libsundials_cvodes.
# cmake -DPROGRAM=<freeflex> -DMODE=bundled|system [-DLIBRARY=<bundled .a>] -DNM=<nm> -P check_sundials_linkage.cmake
find_program(LDD ldd REQUIRED)
execute_process(COMMAND ${LDD} ${PROGRAM} OUTPUT_VARIABLE loaded RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "ldd ${PROGRAM} failed (${rc})")
endif()
if(MODE STREQUAL "system")
  if(NOT loaded MATCHES "libsundials_cvodes")
    message(FATAL_ERROR "FREEFLEX_SUNDIALS=system, but ${PROGRAM} does not load libsundials_cvodes:\n${loaded}")
  endif()
  message(STATUS "${PROGRAM} loads the system's libsundials_cvodes")
  return()
endif()
if(loaded MATCHES "libsundials")
  message(FATAL_ERROR "FREEFLEX_SUNDIALS=bundled, but ${PROGRAM} loads a SUNDIALS shared library:\n${loaded}")
endif()

# name -> size (hex) of the defined text symbols in nm -S output
function(symbol_sizes file out)
  execute_process(COMMAND ${NM} -S --defined-only ${file} OUTPUT_VARIABLE text RESULT_VARIABLE rc ERROR_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${NM} -S ${file} failed (${rc})")
  endif()
  foreach(name CVode N_VLinearSum_Serial N_VWrmsNorm_Serial)
    if(text MATCHES "[0-9a-f]+ ([0-9a-f]+) [Tt] ${name}\n")
      set(${out}_${name} "${CMAKE_MATCH_1}" PARENT_SCOPE)
    else()
      set(${out}_${name} "missing" PARENT_SCOPE)
    endif()
  endforeach()
endfunction()
symbol_sizes(${PROGRAM} prog)
symbol_sizes(${LIBRARY} lib)
foreach(name CVode N_VLinearSum_Serial N_VWrmsNorm_Serial)
  if(prog_${name} STREQUAL "missing" OR NOT prog_${name} STREQUAL lib_${name})
    message(FATAL_ERROR "${name}: size ${prog_${name}} in ${PROGRAM}, ${lib_${name}} in the bundled ${LIBRARY}")
  endif()
  message(STATUS "${name}: 0x${prog_${name}} bytes, as in the bundled library")
endforeach()
