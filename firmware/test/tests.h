/* The test functions, one group per source file. */
#ifndef TESTS_H
#define TESTS_H
void test_numbers(void);
void test_linebuf(void);
void test_linebuf_ring(void);
void test_fmt(void);
void test_ring(void);
void test_gcode_valid(void);
void test_gcode_errors(void);
void test_gcode_grbl_state(void);
void test_gcode_arcs(void);
void test_gcode_pen(void);
void test_gcode_coords(void);
void test_gcode_inverse_time(void);
void test_arc_segments(void);
void test_arc_full_circle(void);
void test_planner_junctions(void);
void test_planner_block_math(void);
void test_planner_cruise_limits(void);
void test_planner_exact_steps(void);
void test_segments_profile(void);
void test_segments_hold(void);
void test_planner_overrides(void);
void test_planner_override_slices(void);
void test_planner_lazy_passes(void);
void test_settings(void);
void test_fuzz_replay(void);
extern const char *fuzz_corpus_dir;
#endif
