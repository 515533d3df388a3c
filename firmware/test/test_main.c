/* Host unit tests of the firmware's pure modules; prints "N passed, N failed". */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "tests.h"

int checks_failed_in_test;
const char *fuzz_corpus_dir = "fuzz/corpus";

static const test_case cases[] = {
    {"numbers", test_numbers},
    {"linebuf", test_linebuf},
    {"linebuf_ring", test_linebuf_ring},
    {"fmt", test_fmt},
    {"ring", test_ring},
    {"gcode_valid", test_gcode_valid},
    {"gcode_errors", test_gcode_errors},
    {"gcode_grbl_state", test_gcode_grbl_state},
    {"gcode_arcs", test_gcode_arcs},
    {"gcode_pen", test_gcode_pen},
    {"gcode_coords", test_gcode_coords},
    {"gcode_inverse_time", test_gcode_inverse_time},
    {"arc_segments", test_arc_segments},
    {"arc_full_circle", test_arc_full_circle},
    {"planner_junctions", test_planner_junctions},
    {"planner_block_math", test_planner_block_math},
    {"planner_cruise_limits", test_planner_cruise_limits},
    {"planner_exact_steps", test_planner_exact_steps},
    {"segments_profile", test_segments_profile},
    {"segments_hold", test_segments_hold},
    {"planner_overrides", test_planner_overrides},
    {"planner_override_slices", test_planner_override_slices},
    {"planner_lazy_passes", test_planner_lazy_passes},
    {"settings", test_settings},
    {"fuzz_replay", test_fuzz_replay},
};

int main(int argc, char **argv)
{
    if (argc > 1)
        fuzz_corpus_dir = argv[1];
    int passed = 0, failed = 0;
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        checks_failed_in_test = 0;
        cases[i].fn();
        if (checks_failed_in_test) {
            printf("FAILED %s\n", cases[i].name);
            failed++;
        } else {
            printf("ok %s\n", cases[i].name);
            passed++;
        }
    }
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
