# Every third-party package the project uses is found here and nowhere else.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(tomlplusplus 3 REQUIRED)
find_package(CLI11 2 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(TBB REQUIRED)
find_package(Threads REQUIRED)
find_package(OpenImageIO 2.4 REQUIRED CONFIG)
# CGAL is header-only here (5.x); relight/ uses its Delaunay triangulations.
find_package(CGAL 5 REQUIRED CONFIG)
# Embree 3: the CPU ray tracing kernels of the virtual light stage (relight/ray_scene).
find_package(embree 3 REQUIRED CONFIG)

if(RFD_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(RFD_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()

# Programs we run rather than link.
find_program(RFD_GNUPLOT gnuplot)
if(NOT RFD_GNUPLOT)
  message(WARNING "gnuplot not found: `rfd optics chart` will write CSV but no plots "
                  "(scripts/install-deps.sh installs it)")
  set(RFD_GNUPLOT "")
endif()
