# Every third-party package the project uses is found here and nowhere else.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(tomlplusplus 3 REQUIRED)
find_package(CLI11 2 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(TBB REQUIRED)
find_package(Threads REQUIRED)
find_package(OpenImageIO 2.4 REQUIRED CONFIG)
# OpenEXR itself: rfd's common EXR files without loading OpenImageIO (core/exr_file.hpp).
find_package(OpenEXR 3.1 REQUIRED CONFIG)
# Cairo: PDF print sheets (print/) and the glyphs of procedural letter fields (patterns/).
find_package(PkgConfig REQUIRED)
pkg_check_modules(Cairo REQUIRED IMPORTED_TARGET cairo)
# XXH3 content hashes for rfd make's manifest (project/manifest.cpp).
pkg_check_modules(xxhash REQUIRED IMPORTED_TARGET libxxhash)
# NLopt (C++ interface): COBYLA, the derivative-free constrained optimiser of `rfd design
# tune` (tune/tune.hpp).
# Debian installs the C and the C++ library's configs side by side under the same package
# name; the C++ one is asked for by its folder.
find_package(NLopt 2.7 REQUIRED CONFIG NO_DEFAULT_PATH
             PATHS /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/nlopt_cxx ${CMAKE_PREFIX_PATH})
if(NOT TARGET NLopt::nlopt_cxx)
  message(FATAL_ERROR "NLopt's C++ library (libnlopt-cxx-dev) not found: run scripts/install-deps.sh")
endif()
# CGAL is header-only here (5.x); relight/ uses its Delaunay triangulations.
find_package(CGAL 5 REQUIRED CONFIG)
# Embree 3: the CPU ray tracing kernels of the virtual light stage (relight/ray_scene).
find_package(embree 3 REQUIRED CONFIG)
# OpenCV 4: HDR assembly (photo: Robertson calibration and merge), the connected
# components of light-calibration highlights (imgproc), and for upsampling the highlight
# inpainting (photo) and optical flow (video), in relight/. Link `rfd_opencv`.
# Debian 12 ships OpenCVConfig.cmake only in libopencv-dev, a metapackage pulling every module
# (76 packages: VTK, Qt, ...); the per-module -dev packages rfd installs hold headers and
# libraries only, so without the config the four modules are found by hand.
find_package(OpenCV 4 QUIET COMPONENTS core imgproc photo video)
add_library(rfd_opencv INTERFACE)
if(OpenCV_FOUND)
  target_link_libraries(rfd_opencv INTERFACE opencv_core opencv_imgproc opencv_photo opencv_video)
else()
  find_path(RFD_OPENCV_INCLUDE_DIR opencv2/photo.hpp PATH_SUFFIXES opencv4 REQUIRED)
  foreach(module video photo imgproc core)  # link order: users first
    find_library(RFD_OPENCV_${module} opencv_${module} REQUIRED)
    target_link_libraries(rfd_opencv INTERFACE ${RFD_OPENCV_${module}})
  endforeach()
  target_include_directories(rfd_opencv SYSTEM INTERFACE ${RFD_OPENCV_INCLUDE_DIR})
endif()

# nanoflann (header only, no CMake config in Debian 12): the k-d tree of image windows that
# upsampling's image-based priors search (relight/image_priors, thesis 6.4.2).
find_path(RFD_NANOFLANN_INCLUDE_DIR nanoflann.hpp REQUIRED)
add_library(rfd_nanoflann INTERFACE)
target_include_directories(rfd_nanoflann SYSTEM INTERFACE ${RFD_NANOFLANN_INCLUDE_DIR})

if(RFD_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(RFD_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()

# Programs we run rather than link.
# oiiotool (openimageio-tools) draws the photographs the capture hdr/calibrate CLI tests read.
find_program(RFD_OIIOTOOL oiiotool)
find_program(RFD_GNUPLOT gnuplot)
if(NOT RFD_GNUPLOT)
  message(WARNING "gnuplot not found: `rfd optics chart` will write CSV but no plots "
                  "(scripts/install-deps.sh installs it)")
  set(RFD_GNUPLOT "")
endif()

# poppler-utils' pdftoppm and pdftocairo render print sheets the way viewers do, for the
# test that their tile joins do not show (tests/test_print.cpp); without them it is skipped.
find_program(RFD_PDFTOPPM pdftoppm)
find_program(RFD_PDFTOCAIRO pdftocairo)
foreach(tool RFD_PDFTOPPM RFD_PDFTOCAIRO)
  if(NOT ${tool})
    set(${tool} "")
  endif()
endforeach()

# OpenSCAD builds the lens holders' STLs (holders/openscad.cpp); without it rfd still
# writes the .scad and says the STL needs openscad.
find_program(RFD_OPENSCAD openscad)
if(NOT RFD_OPENSCAD)
  message(STATUS "openscad not found: rfd holder writes .scad files but cannot build STLs")
  set(RFD_OPENSCAD "")
endif()
