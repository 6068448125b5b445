# The layering of the modules, checked on the sources (ctest module_includes, label unit; run as
# cmake -DSOURCE_DIR=<project> -P tests/module_includes.cmake): the physics owns its parameters
# (fluid/fluid_parameters.hpp, solid/solid_parameters.hpp, coupling/coupling_parameters.hpp), so fluid/ and
# solid/ include nothing from io/, coupling/ or app/, nor each other, and do not link their libraries; core/
# includes only core/; io/ (the case file, output) includes of fluid/, solid/ and coupling/ only their
# parameter headers (*_parameters.hpp) and nothing of app/; coupling/ includes nothing of app/. app/ may include
# everything. Fails listing every offending line.
if(NOT SOURCE_DIR)
  message(FATAL_ERROR "module_includes.cmake: pass -DSOURCE_DIR=<project source dir>")
endif()

# module: the folders its files must not include from
set(forbidden_core io fluid solid coupling app)
set(forbidden_fluid io coupling app solid)
set(forbidden_solid io coupling app fluid)
set(forbidden_io app)
set(forbidden_coupling app)
# module: the folders whose parameter headers alone it may include
set(parameters_only_io fluid solid coupling)

set(offenders "")
foreach(module core fluid solid io coupling)
  file(GLOB files RELATIVE ${SOURCE_DIR} ${SOURCE_DIR}/${module}/*.hpp ${SOURCE_DIR}/${module}/*.cpp)
  foreach(f IN LISTS files)
    file(STRINGS ${SOURCE_DIR}/${f} lines REGEX "^[ \t]*#[ \t]*include[ \t]*[\"<]")
    foreach(line IN LISTS lines)
      foreach(other IN LISTS forbidden_${module})
        if(line MATCHES "include[ \t]*[\"<]${other}/")
          string(STRIP "${line}" line)
          list(APPEND offenders "${f}: ${line} (${module}/ must not include ${other}/)")
        endif()
      endforeach()
      foreach(other IN LISTS parameters_only_${module})
        if(line MATCHES "include[ \t]*[\"<]${other}/" AND NOT line MATCHES "include[ \t]*[\"<]${other}/[a-z_]*_parameters\\.hpp[\">]")
          string(STRIP "${line}" line)
          list(APPEND offenders "${f}: ${line} (${module}/ may include only the parameter headers of ${other}/)")
        endif()
      endforeach()
    endforeach()
  endforeach()
endforeach()

# ... and their libraries link none of those either.
foreach(module fluid solid)
  file(READ ${SOURCE_DIR}/${module}/CMakeLists.txt cmake_text)
  foreach(other IN LISTS forbidden_${module})
    if(cmake_text MATCHES "mpsfsi_${other}[ \t\n)]")
      list(APPEND offenders "${module}/CMakeLists.txt: links mpsfsi_${other} (${module}/ must not depend on ${other}/)")
    endif()
  endforeach()
endforeach()

if(offenders)
  list(LENGTH offenders n)
  string(REPLACE ";" "\n  " text "${offenders}")
  message(FATAL_ERROR "module_includes: ${n} forbidden include(s):\n  ${text}")
endif()
message(STATUS "module_includes: core/, fluid/, solid/, io/ and coupling/ include only what their layer allows")
