# rfd holder end to end: the Design I holder built and checked through the CLI (JSON
# report: every part a single closed solid, seats within 0.05 mm, no ray blocked); a Design
# II with overlapping pockets and a bad printer profile rejected with exit code 2 before
# anything is written; the pattern's pocket sized by the film printer; a small fit-test
# coupon. (The unit tests build every design's
# holder and the full-size coupon; this checks what the command adds.)
include(${CMAKE_CURRENT_LIST_DIR}/run_rfd.cmake)
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})

run(0 holder ${DESIGN1} --out ${OUT}/holder.scad --stl ${OUT}/holder.stl --json)
foreach(part base lid)
  if(NOT EXISTS ${OUT}/holder_${part}.stl)
    message(FATAL_ERROR "holder_${part}.stl was not written")
  endif()
endforeach()
string(JSON blocked GET "${last_output}" beam_clearance blocked)
string(JSON rays GET "${last_output}" beam_clearance rays)
if(NOT blocked EQUAL 0 OR rays LESS 1000)
  message(FATAL_ERROR "beam clearance: ${blocked} of ${rays} rays blocked")
endif()
string(JSON problems LENGTH "${last_output}" problems)
if(NOT problems EQUAL 0)
  message(FATAL_ERROR "the holder reported problems:\n${last_output}")
endif()
string(JSON components GET "${last_output}" parts 0 components)
if(NOT components EQUAL 1)
  message(FATAL_ERROR "the base has ${components} pieces")
endif()

# The diffuser moved so close behind the corrective pair that the pockets overlap.
file(READ ${DESIGN2} text)
string(REPLACE "z_mm = 25.1278" "z_mm = 13.8" text "${text}")
file(WRITE ${OUT}/overlapping.toml "${text}")
run(2 holder ${OUT}/overlapping.toml --out ${OUT}/overlapping.scad --stl ${OUT}/overlapping.stl)
expect("overlapping.toml:[0-9]+.*overlaps the pocket of plane B")
if(EXISTS ${OUT}/overlapping.scad OR EXISTS ${OUT}/overlapping_base.stl)
  message(FATAL_ERROR "a rejected design left files behind")
endif()

file(WRITE ${OUT}/profile.toml "[printer]\nclearance_mm = 0.2\nwall_mm = 2\n")
run(2 holder ${DESIGN2} --out ${OUT}/p.scad --3d-printer ${OUT}/profile.toml)
expect("profile.toml:3.*wall_mm")

# The pattern's pocket keeps room for the film printer's sheets: the Epson (the default)
# prints two, the 720 dpi inkjet one; a pattern encoded for the inkjet carries it.
run(0 holder ${DESIGN2} --out ${OUT}/epson.scad)
expect("pattern film: 2 sheet\\(s\\) of 0.1 mm, from printer 'Epson Stylus Pro 4800'")
file(READ ${OUT}/epson.scad scad)
if(NOT scad MATCHES "\npattern_sheets = 2;")
  message(FATAL_ERROR "the default holder does not keep room for two sheets")
endif()
run(0 holder ${DESIGN2} --printer inkjet_720 --out ${OUT}/inkjet.scad)
expect("pattern film: 1 sheet\\(s\\) of 0.1 mm, from printer 'generic 720 dpi inkjet'")
file(READ ${OUT}/inkjet.scad scad)
if(NOT scad MATCHES "\npattern_sheets = 1;")
  message(FATAL_ERROR "the inkjet's holder does not keep room for one sheet")
endif()

run(0 holder coupon --out ${OUT}/coupon.scad --stl ${OUT}/coupon.stl --diameter 6 --square 5)
expect("9 seat rings")
expect("volume")
