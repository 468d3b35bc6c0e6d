# `rfd pattern field` and `rfd pattern encode` end to end on Design II at a low resolution:
#  - a procedural field is written and encoded; the pattern has the size and resolution the
#    design asks for, and encoding twice gives byte-identical files;
#  - a field whose lights do not reach the display's range is refused (exit 2) with the
#    directions, and nothing is written;
#  - an unwritable output is an I/O error (exit 3).
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)

run(0 pattern field bars --resolution 12x10 --spread 8 --out ${OUT}/bars)
foreach(name a b)
  run(0 pattern encode ${DESIGN} ${OUT}/bars --dpi 360x180 --out ${OUT}/${name}.exr --json)
endforeach()
# 24 mm at 360 x 180 dpi: 341 x 171 dots (whole dots covering the array).
if(NOT last_output MATCHES "\"width\": 341" OR NOT last_output MATCHES "\"height\": 171")
  message(FATAL_ERROR "unexpected pattern size: ${last_output}")
endif()
expect_same_file(${OUT}/a.exr ${OUT}/b.exr "encoding twice gave different files")

# A pattern with a blank margin prints: the file records its margin, so the printer's tools
# rebuild the same raster (28 mm at 720 x 360 dpi: 794 x 397 dots).
run(0 pattern encode ${DESIGN} ${OUT}/bars --dpi 720x360 --margin 2 --out ${OUT}/margin.exr --json)
if(NOT last_output MATCHES "\"width\": 794" OR NOT last_output MATCHES "\"height\": 397")
  message(FATAL_ERROR "unexpected pattern size with a margin: ${last_output}")
endif()
run(0 print sheet ${DESIGN} ${OUT}/margin.exr --printer ${PRINTER} --out ${OUT}/margin.tif)

# The printer travels with the pattern: encoded for the 720 dpi inkjet, it prints and
# simulates at 720 dpi without --printer; another printer given by hand is refused, naming
# both.
run(0 pattern encode ${DESIGN} ${OUT}/bars --printer inkjet_720 --out ${OUT}/inkjet.exr)
run(0 print sheet ${DESIGN} ${OUT}/inkjet.exr --out ${OUT}/inkjet.tif)
expect("at 720 x 720 dpi")
run(0 simulate ${DESIGN} ${OUT}/inkjet.exr --light 0,0 --out ${OUT}/inkjet.png)
run(2 print sheet ${DESIGN} ${OUT}/inkjet.exr --printer epson_stylus_pro_4800 --out ${OUT}/never.tif)
expect("encoded for printer 'generic 720 dpi inkjet', but --printer epson_stylus_pro_4800 is 'Epson Stylus Pro 4800'")
run(2 pattern encode ${DESIGN} ${OUT}/bars --printer inkjet_720 --dpi 360 --out ${OUT}/never.exr)
expect("--dpi 360 disagrees with --printer inkjet_720")

# A narrow field: four lights near the zenith, rendered from the light file.
run(0 capture render ${SCENE} --lights ${NARROW} --resolution 8x4 --samples-per-pixel 1 --out ${OUT}/narrow)
run(2 pattern encode ${DESIGN} ${OUT}/narrow --dpi 360 --out ${OUT}/narrow.exr)
if(NOT last_output MATCHES "does not cover the display's angular range" OR NOT last_output MATCHES "display theta [0-9.]+ deg, phi")
  message(FATAL_ERROR "unexpected message: ${last_output}")
endif()
if(EXISTS ${OUT}/narrow.exr)
  message(FATAL_ERROR "a refused pattern was written")
endif()

run(3 pattern encode ${DESIGN} ${OUT}/bars --dpi 360 --out /proc/rfd-no-such-dir/p.exr)
if(NOT last_output MATCHES "does not exist")
  message(FATAL_ERROR "unexpected message: ${last_output}")
endif()
