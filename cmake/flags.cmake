# Warning and sanitizer flags live in INTERFACE targets that every target of ours links.
add_library(rfd_warnings INTERFACE)
target_compile_options(rfd_warnings INTERFACE -Wall -Wextra -Wpedantic -Wshadow
                       -Wnon-virtual-dtor -Wconversion -Wno-sign-conversion
                       # Value types with defaulted fields are meant to be partly initialised.
                       -Wno-missing-field-initializers)
# GCC 12 reports false -Wrestrict warnings inside std::string concatenation at -O3
# (GCC bug 105329); they are not ours to fix.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  target_compile_options(rfd_warnings INTERFACE -Wno-restrict)
endif()
if(RFD_WERROR)
  target_compile_options(rfd_warnings INTERFACE -Werror)
endif()

add_library(rfd_sanitizers INTERFACE)
if(RFD_SANITIZE)
  target_compile_options(rfd_sanitizers INTERFACE
                         -fsanitize=address,undefined -fno-omit-frame-pointer
                         -fno-sanitize-recover=undefined)
  target_link_options(rfd_sanitizers INTERFACE -fsanitize=address,undefined)
  # The sanitizers' metadata (a descriptor per global, a source location per check) makes a
  # position-independent program carry about 1.8 million relative relocations, applied at
  # every start: 0.4 s of CPU each time a test starts rfd_tests or rfd, more than most unit
  # tests take. Programs of the sanitizer build are linked at a fixed address instead
  # (address-space randomisation protects nothing in a test build); the Release build keeps PIE.
  target_link_options(rfd_sanitizers INTERFACE $<$<STREQUAL:$<TARGET_PROPERTY:TYPE>,EXECUTABLE>:-no-pie>)
endif()
# libFuzzer's coverage counters in all of rfd's code; the fuzz programs link the fuzzer
# itself (fuzz/CMakeLists.txt). Third-party libraries stay as installed.
if(RFD_BUILD_FUZZ AND RFD_FUZZ_ENGINE STREQUAL "libfuzzer")
  target_compile_options(rfd_sanitizers INTERFACE -fsanitize=fuzzer-no-link)
endif()

# -fno-trapping-math: rfd never reads floating-point exception flags, so the compiler may
# evaluate both arms of a select; without it GCC will not vectorise the masked loops of the
# batch tracers. Unlike -ffast-math it changes no computed value.
# -fno-math-errno: rfd never reads errno after a math call, so std::sqrt is one instruction
# and loops of square roots vectorise (the pattern renderer's 1/cos(kappa)). No value changes.
# -ffp-contract=off: no fused multiply-adds, so the kernels compiled for AVX2 machines
# (target_clones) give the same bits as the baseline build: outputs do not depend on the CPU.
add_library(rfd_codegen INTERFACE)
target_compile_options(rfd_codegen INTERFACE -fno-trapping-math -fno-math-errno -ffp-contract=off)

add_library(rfd_flags INTERFACE)
target_link_libraries(rfd_flags INTERFACE rfd_warnings rfd_sanitizers rfd_codegen)

# Modules (core/module.hpp): librfd_NAME.so beside the programs, opened with dlopen on first
# use; target rfd_NAME_module. A module resolves everything it needs from its own libraries
# (--no-undefined) and exports only its entry point.
set(RFD_MODULE_DIR ${CMAKE_BINARY_DIR}/bin)
function(rfd_add_module name)
  set(target rfd_${name}_module)
  add_library(${target} MODULE ${ARGN})
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR})
  target_link_libraries(${target} PRIVATE rfd_flags)
  # clang links its sanitizer runtimes into programs only, so a sanitized module finds
  # them in the program that loads it.
  if(NOT (RFD_SANITIZE AND CMAKE_CXX_COMPILER_ID STREQUAL "Clang"))
    target_link_options(${target} PRIVATE -Wl,--no-undefined)
  endif()
  set_target_properties(${target} PROPERTIES OUTPUT_NAME rfd_${name} LIBRARY_OUTPUT_DIRECTORY ${RFD_MODULE_DIR}
                        CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
endfunction()

# Unity builds: each library compiles as a few large files, so the headers every file
# includes (Eigen, TBB, nlohmann-json, the standard library: 2-4 s each to parse) and the
# templates they instantiate are compiled once per batch instead of once per file. A clean
# build takes about a third less; an edit recompiles its batch. RFD_UNITY_BUILD=OFF builds
# file by file (HACKING.md: the check that each file includes what it uses).
option(RFD_UNITY_BUILD "Compile each library as a few large files" ON)
function(rfd_unity_build target)
  if(RFD_UNITY_BUILD)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8)
  endif()
endfunction()
