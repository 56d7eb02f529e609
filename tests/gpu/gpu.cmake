# The Vulkan compute harness of the GPU tests and its smoke test. Included from
# tests/CMakeLists.txt after find_package(GTest) and include(GoogleTest).
#
# REQUIRED throughout: a machine without Vulkan or the shader tools should fail at
# configure time, not pass its GPU tests by skipping them (SHTOOL_SKIP_GPU_TESTS=1 at
# run time is the explicit opt-out for a developer without a Vulkan device).
find_package(Vulkan REQUIRED)
find_program(SHTOOL_GLSLANG_VALIDATOR glslangValidator REQUIRED)
find_program(SHTOOL_SPIRV_VAL spirv-val REQUIRED)

add_library(shtool_gpu_harness STATIC ${CMAKE_CURRENT_LIST_DIR}/vulkan_compute.cpp)
target_include_directories(shtool_gpu_harness PUBLIC ${CMAKE_CURRENT_LIST_DIR})
target_link_libraries(shtool_gpu_harness PUBLIC Vulkan::Vulkan GTest::gtest PRIVATE ${CMAKE_DL_LIBS})
target_compile_definitions(shtool_gpu_harness PUBLIC
  SHTOOL_GLSLANG_VALIDATOR="${SHTOOL_GLSLANG_VALIDATOR}"
  SHTOOL_SPIRV_VAL="${SHTOOL_SPIRV_VAL}")

add_executable(test_vulkan_harness ${CMAKE_CURRENT_LIST_DIR}/test_vulkan_harness.cpp)
target_link_libraries(test_vulkan_harness PRIVATE shtool_gpu_harness GTest::gtest_main)
shtool_register_gtest(test_vulkan_harness LABELS gpu)
