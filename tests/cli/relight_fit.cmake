# `rfd relight fit` and relighting its fits end to end on a small rendered field:
#  - --basis auto says every candidate's leave-one-out PSNR and chooses the best of them (linear
#    PSNR for this float field);
#  - a fit is written the same, byte for byte, twice; it relights under --light-dir and a
#    light file; an rbf fit keeps --planes components, three to a plane file; a bilinear fit
#    records its grid's side and relights;
#  - what the format cannot hold (hsh4 in JPEG planes) and field options given with a fit are
#    input errors that say so; relight eval --leave-one-out scores rbf with its sigma.
file(REMOVE_RECURSE ${OUT})
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)

run(0 capture render ${SCENE} --samples-per-pixel 1 --resolution 40x30 --lights 24 --out ${OUT}/field)

run(0 relight fit ${OUT}/field --out ${OUT}/auto --json)
string(JSON chosen GET "${last_output}" basis)
string(JSON count LENGTH "${last_output}" candidates)
math(EXPR last "${count} - 1")
set(best_name "")
set(best_db -1000)
foreach(i RANGE ${last})
  string(JSON name GET "${last_output}" candidates ${i} basis)
  string(JSON db GET "${last_output}" candidates ${i} mean_psnr_linear_db)
  if(db GREATER best_db)
    set(best_db ${db})
    set(best_name ${name})
  endif()
endforeach()
if(NOT count EQUAL 5 OR NOT chosen STREQUAL best_name)
  message(FATAL_ERROR "auto chose ${chosen}; the best of ${count} candidates is ${best_name}: ${last_output}")
endif()

run(0 relight fit ${OUT}/field --basis hsh3 --out ${OUT}/a)
expect("fitted hsh3 .* 27 planes in 9 JPEG file")
run(0 relight fit ${OUT}/field --basis hsh3 --out ${OUT}/b)
foreach(file info.json plane_0.jpg plane_8.jpg)
  expect_same_file(${OUT}/a/${file} ${OUT}/b/${file} "two identical fits differ in ${file}")
endforeach()

run(0 relight render ${OUT}/a --light-dir 0.3,0.1,0.9 --out ${OUT}/one.png --light 40,90 --out ${OUT}/two.exr)
expect("relit the hsh fit .* into 2 image")
if(NOT EXISTS ${OUT}/two.exr)
  message(FATAL_ERROR "relighting a fit wrote no two.exr")
endif()
run(0 relight render ${OUT}/a/info.json --lights ${OUT}/field/field.lp --out ${OUT}/own)
if(NOT EXISTS ${OUT}/own/field_0023.exr)
  message(FATAL_ERROR "relighting a fit under the capture's light file wrote no field_0023.exr")
endif()
run(2 relight render ${OUT}/a --light 0,0 --basis ptm --out ${OUT}/never.png)
expect("is a fit; --envmap, --basis, --region and --scale are for fields")
run(2 relight render ${OUT}/a --light 0,0,20 --out ${OUT}/never.png)
expect("white distant point lights")

run(0 relight fit ${OUT}/field --basis rbf --planes 6 --out ${OUT}/rbf)
expect("6 planes in 2 JPEG file.*rbf: sigma [0-9.]+, 6 principal components keep")
run(0 relight render ${OUT}/rbf --light 20,30 --out ${OUT}/rbf.png)
run(0 relight fit ${OUT}/field --basis bilinear --resolution 6 --planes 9 --out ${OUT}/bilinear)
expect("9 planes in 3 JPEG file.*bilinear: a 6 x 6 grid .prior sigma [0-9.]+., 9 principal components keep")
file(READ ${OUT}/bilinear/info.json info)
string(JSON type GET "${info}" type)
string(JSON resolution GET "${info}" resolution)
string(JSON basis_bytes LENGTH "${info}" basis)
if(NOT type STREQUAL "bilinear" OR NOT resolution EQUAL 6 OR NOT basis_bytes EQUAL 1080)
  message(FATAL_ERROR "a bilinear fit of a 6 x 6 grid and 9 planes: type ${type}, resolution ${resolution}, "
                      "${basis_bytes} basis bytes (expected 10 x 36 x 3 = 1080)")
endif()
run(0 relight render ${OUT}/bilinear --light 20,30 --out ${OUT}/bilinear.png)
expect("relit the bilinear fit")

run(2 relight fit ${OUT}/field --basis hsh4 --out ${OUT}/never)
expect("hsh4 .16 functions. is beyond what OpenLIME renders")
run(0 relight fit ${OUT}/field --basis hsh4 --exact --out ${OUT}/hsh4)
if(NOT EXISTS ${OUT}/hsh4/plane_15.exr)
  message(FATAL_ERROR "an exact hsh4 fit has 16 float plane files: ${last_output}")
endif()

run(0 relight eval ${OUT}/field --leave-one-out --basis rbf --basis ptm --basis bilinear --json)
string(JSON sigma GET "${last_output}" bases rbf sigma)
string(JSON prior GET "${last_output}" bases bilinear sigma)
if(NOT sigma GREATER 0 OR NOT prior GREATER 0)
  message(FATAL_ERROR "leave-one-out of rbf or bilinear without its sigma: ${last_output}")
endif()
