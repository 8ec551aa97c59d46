# Shared CMake conventions of the tactile flight workspace.
#
# Every package does:
#
#   find_package(tactile_common REQUIRED)
#   tactile_package_setup()                 # C++17, warnings, ROS 2 detection
#   add_library(foo ...)                    # core + node logic (never ROS)
#   tactile_install_targets(foo)            # install + export foo::foo
#   if(TACTILE_WITH_ROS)                    # rclcpp component, ROS builds only
#     ...
#   endif()
#   tactile_add_gtest(test_foo test/test_foo.cpp LIBRARIES foo)
#   tactile_package_finish(DEPENDENCIES Eigen3 tactile_msgs)
#
# Without ROS 2 the package exports a plain CMake config
# (share/<pkg>/cmake/<pkg>Config.cmake) and installs the local_setup.* hooks
# that colcon's ament_cmake build type expects, so sourcing install/setup.bash
# prints no "not found" warnings. With ROS 2 (ament_cmake and rclcpp found)
# the same targets are exported through ament and ament_package() writes the
# hooks.

include_guard(GLOBAL)
include(CMakePackageConfigHelpers)
include(GNUInstallDirs)

macro(tactile_package_setup)
  if(NOT CMAKE_CXX_STANDARD)
    set(CMAKE_CXX_STANDARD 17)
  endif()
  set(CMAKE_CXX_STANDARD_REQUIRED ON)
  set(CMAKE_CXX_EXTENSIONS OFF)
  set(CMAKE_POSITION_INDEPENDENT_CODE ON)
  if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
    set(CMAKE_BUILD_TYPE RelWithDebInfo)
  endif()
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    add_compile_options(-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion)
  endif()
  option(TACTILE_BUILD_BENCHMARKS "Build the Google Benchmark targets" ON)
  # ROS 2 is optional. TACTILE_FORCE_NO_ROS=ON builds the ROS-free layers only
  # even where ROS 2 is sourced.
  option(TACTILE_FORCE_NO_ROS "Do not build rclcpp components even if ROS 2 is found" OFF)
  set(TACTILE_WITH_ROS OFF)
  if(NOT TACTILE_FORCE_NO_ROS)
    find_package(ament_cmake QUIET)
    find_package(rclcpp QUIET)
    find_package(rclcpp_components QUIET)
    if(ament_cmake_FOUND AND rclcpp_FOUND AND rclcpp_components_FOUND)
      set(TACTILE_WITH_ROS ON)
    endif()
  endif()
  if(TACTILE_WITH_ROS)
    message(STATUS "${PROJECT_NAME}: ROS 2 found, building the rclcpp component")
  else()
    message(STATUS "${PROJECT_NAME}: ROS 2 not found, building core and node logic only")
  endif()
  # include(CTest) defines BUILD_TESTING (default ON) and writes the
  # DartConfiguration.tcl that colcon's ctest invocation expects.
  include(CTest)
  if(BUILD_TESTING)
    find_package(GTest REQUIRED)
    include(GoogleTest)
  endif()
  set(_TACTILE_EXPORTED_TARGETS "")
endmacro()

# tactile_install_targets(<target>...): install libraries/executables and add
# them to the package's exported target set <pkg>::<target>.
function(tactile_install_targets)
  foreach(_t ${ARGN})
    target_include_directories(${_t} INTERFACE $<INSTALL_INTERFACE:include>)
  endforeach()
  install(TARGETS ${ARGN}
    EXPORT ${PROJECT_NAME}Targets
    ARCHIVE DESTINATION lib
    LIBRARY DESTINATION lib
    RUNTIME DESTINATION bin
    INCLUDES DESTINATION include)
  set_property(GLOBAL APPEND PROPERTY TACTILE_${PROJECT_NAME}_EXPORTED ${ARGN})
endfunction()

# tactile_add_gtest(<name> <sources>... [LIBRARIES <libs>...] [TIMEOUT <s>])
function(tactile_add_gtest name)
  if(NOT BUILD_TESTING)
    return()
  endif()
  cmake_parse_arguments(ARG "" "TIMEOUT" "LIBRARIES" ${ARGN})
  add_executable(${name} ${ARG_UNPARSED_ARGUMENTS})
  target_link_libraries(${name} PRIVATE ${ARG_LIBRARIES} GTest::gtest GTest::gtest_main)
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  gtest_discover_tests(${name}
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}
    PROPERTIES TIMEOUT ${ARG_TIMEOUT}
    DISCOVERY_TIMEOUT 60)
endfunction()

# tactile_add_pytest(<name> <test file or dir> [ENVIRONMENT k=v...]): a Python
# test run with the interpreter of the active virtual environment
# (scripts/test.sh activates .venv before building).
function(tactile_add_pytest name path)
  if(NOT BUILD_TESTING)
    return()
  endif()
  cmake_parse_arguments(ARG "" "TIMEOUT" "ENVIRONMENT" ${ARGN})
  find_package(Python3 COMPONENTS Interpreter REQUIRED)
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  add_test(NAME ${name}
    COMMAND ${Python3_EXECUTABLE} -m pytest -q -p no:cacheprovider ${path}
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
  set_tests_properties(${name} PROPERTIES TIMEOUT ${ARG_TIMEOUT}
    ENVIRONMENT "${ARG_ENVIRONMENT}")
endfunction()

# tactile_add_benchmark(<name> <sources>... [LIBRARIES <libs>...]): a Google
# Benchmark executable, built but never run by the test suite.
function(tactile_add_benchmark name)
  if(NOT TACTILE_BUILD_BENCHMARKS)
    return()
  endif()
  find_package(benchmark QUIET)
  if(NOT benchmark_FOUND)
    message(STATUS "${PROJECT_NAME}: Google Benchmark not found, skipping ${name}")
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "LIBRARIES" ${ARGN})
  add_executable(${name} ${ARG_UNPARSED_ARGUMENTS})
  target_link_libraries(${name} PRIVATE ${ARG_LIBRARIES} benchmark::benchmark)
  install(TARGETS ${name} RUNTIME DESTINATION lib/${PROJECT_NAME})
endfunction()

# tactile_package_finish([DEPENDENCIES <find_package names>...] [CONFIG_EXTRAS <file.cmake>])
# Exports the installed targets and writes the package config. DEPENDENCIES are
# the packages the exported targets link to (find_dependency in the config).
# CONFIG_EXTRAS is a CMake file included by the package config.
macro(tactile_package_finish)
  cmake_parse_arguments(_TPF "" "CONFIG_EXTRAS" "DEPENDENCIES" ${ARGN})
  install(DIRECTORY include/ DESTINATION include OPTIONAL)
  if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/config)
    install(DIRECTORY config/ DESTINATION share/${PROJECT_NAME}/config)
  endif()
  get_property(_tpf_targets GLOBAL PROPERTY TACTILE_${PROJECT_NAME}_EXPORTED)
  if(TACTILE_WITH_ROS)
    if(_tpf_targets)
      ament_export_targets(${PROJECT_NAME}Targets HAS_LIBRARY_TARGET)
    endif()
    if(_TPF_DEPENDENCIES)
      ament_export_dependencies(${_TPF_DEPENDENCIES})
    endif()
    if(_TPF_CONFIG_EXTRAS)
      ament_package(CONFIG_EXTRAS ${_TPF_CONFIG_EXTRAS})
    else()
      ament_package()
    endif()
  else()
    set(_tpf_config "${CMAKE_CURRENT_BINARY_DIR}/${PROJECT_NAME}Config.cmake")
    set(_tpf_content "# Generated by tactile_common for ${PROJECT_NAME}\ninclude(CMakeFindDependencyMacro)\n")
    foreach(_dep ${_TPF_DEPENDENCIES})
      if(_dep STREQUAL "Eigen3")
        string(APPEND _tpf_content "find_dependency(Eigen3 3.3 NO_MODULE)\n")
      else()
        string(APPEND _tpf_content "find_dependency(${_dep})\n")
      endif()
    endforeach()
    if(_TPF_CONFIG_EXTRAS)
      get_filename_component(_tpf_extra_name ${_TPF_CONFIG_EXTRAS} NAME)
      install(FILES ${_TPF_CONFIG_EXTRAS} DESTINATION share/${PROJECT_NAME}/cmake)
      string(APPEND _tpf_content "include(\"\${CMAKE_CURRENT_LIST_DIR}/${_tpf_extra_name}\")\n")
    endif()
    if(_tpf_targets)
      string(APPEND _tpf_content "include(\"\${CMAKE_CURRENT_LIST_DIR}/${PROJECT_NAME}Targets.cmake\")\n")
    endif()
    string(APPEND _tpf_content "set(${PROJECT_NAME}_FOUND TRUE)\n")
    file(WRITE "${_tpf_config}" "${_tpf_content}")
    write_basic_package_version_file(
      ${CMAKE_CURRENT_BINARY_DIR}/${PROJECT_NAME}ConfigVersion.cmake
      VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
    install(FILES ${_tpf_config} ${CMAKE_CURRENT_BINARY_DIR}/${PROJECT_NAME}ConfigVersion.cmake
      DESTINATION share/${PROJECT_NAME}/cmake)
    if(_tpf_targets)
      install(EXPORT ${PROJECT_NAME}Targets NAMESPACE ${PROJECT_NAME}::
        DESTINATION share/${PROJECT_NAME}/cmake)
    endif()
    install(FILES package.xml DESTINATION share/${PROJECT_NAME})
    # colcon's ament_cmake build type sources share/<pkg>/local_setup.<ext>
    # for every shell; ament_package() would write them. Without ament the
    # package needs no environment of its own beyond what colcon's own hooks
    # set (PATH, LD_LIBRARY_PATH, CMAKE_PREFIX_PATH), so they are empty.
    foreach(_ext sh bash zsh dsv ps1)
      file(WRITE "${CMAKE_CURRENT_BINARY_DIR}/local_setup.${_ext}"
        "# ${PROJECT_NAME}: no package-specific environment (ROS-free build)\n")
    endforeach()
    file(WRITE "${CMAKE_CURRENT_BINARY_DIR}/local_setup.dsv" "")
    foreach(_ext sh bash zsh dsv ps1)
      install(FILES "${CMAKE_CURRENT_BINARY_DIR}/local_setup.${_ext}"
        DESTINATION share/${PROJECT_NAME})
    endforeach()
  endif()
endmacro()
