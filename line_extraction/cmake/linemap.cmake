# The shared CMake blocks of every linemap package, written once. line_extraction includes this file
# itself; every package that finds it through catkin (find_package(catkin REQUIRED COMPONENTS
# line_extraction ...)) gets it from line_extraction's CFG_EXTRAS.
#
#   linemap_package()                                  C++17, warnings, build type (call after project())
#   linemap_core_library(NAME SOURCES...)             a ROS-free core library
#   linemap_core_libraries(OUT PACKAGE...)             the found packages' core libraries alone
#   linemap_add_nodelet(NAME SOURCE LIBRARIES...)      a nodelet library, installed
#   linemap_add_node(NAME SOURCE)                      a stand-alone node, installed
#   linemap_add_executables(DIR LIBRARIES... [INSTALL]) every DIR/*.cpp an executable (tools, benchmarks)
#   linemap_add_gtests(LIBRARIES...)                   every test/test_*.cpp a gtest
#   linemap_add_rostests(DIR...)                       every DIR/*.test a rostest
#   linemap_install_libraries(TARGET...)               the install rule of libraries

# The shared preamble: a macro, so that the settings land in the calling package's scope.
macro(linemap_package)
  set(CMAKE_CXX_STANDARD 17)
  set(CMAKE_CXX_STANDARD_REQUIRED ON)
  if(NOT CMAKE_BUILD_TYPE)
    set(CMAKE_BUILD_TYPE Release)
  endif()
  # Every target of the package (core, nodelets, tools, tests, benchmarks) warns at -Wall -Wextra; none
  # is expected.
  add_compile_options(-Wall -Wextra)
  # Boost.Geometry/Boost.Math include headers Boost deprecated; Boost's documented define silences their
  # "This header is deprecated" pragma messages at the source (our own warnings stay on).
  add_definitions(-DBOOST_ALLOW_DEPRECATED_HEADERS)
endmacro()

# A ROS-free core library: the package's include/ public, optimised even in a sanitizer build (which
# clears the Release flags), position independent so that the nodelet libraries can link it.
function(linemap_core_library name)
  add_library(${name} ${ARGN})
  target_include_directories(${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_compile_options(${name} PRIVATE -O3)
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
endfunction()

# The core libraries of the given packages (the libraries each exports under its own name, <pkg>_*),
# without the ROS libraries they also export: targets of this build (catkin_make builds every package in one CMake project) or the libraries' paths (catkin build
# gives each package a build of its own).
function(linemap_core_libraries out)
  set(cores "")
  foreach(pkg ${ARGN})
    set(libs ${${pkg}_LIBRARIES})
    list(FILTER libs INCLUDE REGEX "(^|/)(lib)?${pkg}_[^/]*$")
    list(APPEND cores ${libs})
  endforeach()
  list(REMOVE_DUPLICATES cores)
  set(${out} ${cores} PARENT_SCOPE)
endfunction()

function(linemap_install_libraries)
  install(TARGETS ${ARGN}
    ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
    LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
    RUNTIME DESTINATION ${CATKIN_GLOBAL_BIN_DESTINATION})
endfunction()

# linemap_add_nodelet(NAME SOURCE LIBRARIES lib...): a nodelet library over the given libraries.
function(linemap_add_nodelet name source)
  cmake_parse_arguments(ARG "" "" "LIBRARIES" ${ARGN})
  add_library(${name} ${source})
  target_include_directories(${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include ${catkin_INCLUDE_DIRS})
  target_link_libraries(${name} ${ARG_LIBRARIES} ${catkin_LIBRARIES})
  if(catkin_EXPORTED_TARGETS)
    add_dependencies(${name} ${catkin_EXPORTED_TARGETS})
  endif()
  linemap_install_libraries(${name})
endfunction()

# linemap_add_node(NAME SOURCE): a node that loads the package's nodelet in a process of its own.
function(linemap_add_node name source)
  add_executable(${name} ${source})
  target_include_directories(${name} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/include ${catkin_INCLUDE_DIRS})
  target_link_libraries(${name} ${catkin_LIBRARIES})
  install(TARGETS ${name} RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endfunction()

# linemap_add_executables(DIR LIBRARIES lib... [INSTALL] [BENCHMARK]): every DIR/*.cpp an executable
# named after its file. BENCHMARK links Google Benchmark when it is installed; INSTALL installs each
# as `rosrun <package> <name>`.
function(linemap_add_executables dir)
  cmake_parse_arguments(ARG "INSTALL;BENCHMARK" "" "LIBRARIES" ${ARGN})
  if(ARG_BENCHMARK)
    find_package(benchmark QUIET)
  endif()
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/*.cpp)
  foreach(src ${sources})
    get_filename_component(name ${src} NAME_WE)
    add_executable(${name} ${src})
    target_include_directories(${name} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/include ${catkin_INCLUDE_DIRS})
    target_link_libraries(${name} ${ARG_LIBRARIES})
    if(catkin_EXPORTED_TARGETS)
      add_dependencies(${name} ${catkin_EXPORTED_TARGETS})
    endif()
    if(ARG_BENCHMARK)
      # Optimised even in a sanitizer build, like the cores they time.
      target_compile_options(${name} PRIVATE -O3)
      if(benchmark_FOUND)
        target_link_libraries(${name} benchmark::benchmark)
      endif()
    endif()
    if(ARG_INSTALL)
      install(TARGETS ${name} RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
    endif()
  endforeach()
endfunction()

# linemap_add_gtests(LIBRARIES lib...): every test/test_*.cpp a gtest named after its file, run from the
# package directory, with LINEMAP_SOURCE_DIR the repository root (for the datasets beside it). These
# are what `make check` runs.
function(linemap_add_gtests)
  cmake_parse_arguments(ARG "" "" "LIBRARIES" ${ARGN})
  if(NOT CATKIN_ENABLE_TESTING)
    return()
  endif()
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test/test_*.cpp)
  foreach(src ${sources})
    get_filename_component(name ${src} NAME_WE)
    catkin_add_gtest(${name} ${src} WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
    target_include_directories(${name} PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/include ${catkin_INCLUDE_DIRS})
    target_link_libraries(${name} ${ARG_LIBRARIES} gtest_main)
    target_compile_definitions(${name} PRIVATE LINEMAP_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}/..")
  endforeach()
endfunction()

# linemap_add_rostests(DIR...): every DIR/*.test a rostest (DIR relative to the package; `../test` is the
# repository's system suite).
function(linemap_add_rostests)
  if(NOT CATKIN_ENABLE_TESTING)
    return()
  endif()
  find_package(rostest REQUIRED)
  foreach(dir ${ARGN})
    file(GLOB tests CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/*.test)
    foreach(t ${tests})
      add_rostest(${t})
    endforeach()
  endforeach()
endfunction()
