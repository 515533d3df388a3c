/* G-code parser: valid lines, every error path we promise, arcs, pen words. */
#include <math.h>
#include <string.h>
#include "check.h"
#include "gcode.h"
#include "host_store.h"
#include "status.h"
#include "tests.h"

static gc_state_t st;
static gc_block_t blk;

/* parse a line and commit its modal state as protocol.c does: in place,
 * put back on an error (jogs parse into a second state: below) */
static gc_state_t undo;
static uint8_t parse(const char *line)
{
    uint8_t e = gc_parse(line, &st, &blk, 0, &undo);
    if (e)
        gc_undo(&st, &undo, &blk);
    return e;
}

void test_gcode_valid(void)
{
    gc_init(&st);
    CHECK(parse("G21G90") == STATUS_OK && blk.action == ACT_NONE);
    CHECK(parse("G0X10Y5") == STATUS_OK && blk.action == ACT_RAPID);
    CHECK_NEAR(blk.target[0], 10, 1e-6);
    CHECK_NEAR(blk.target[1], 5, 1e-6);
    CHECK(parse("G1X20F3000") == STATUS_OK && blk.action == ACT_LINE);
    CHECK_NEAR(blk.feed, 3000, 1e-3);
    CHECK_NEAR(blk.target[1], 5, 1e-6);
    /* modal G1 and feed carry over */
    CHECK(parse("Y7") == STATUS_OK && blk.action == ACT_LINE && blk.feed == 3000.0f);
    /* incremental */
    CHECK(parse("G91X1Y-1") == STATUS_OK);
    CHECK_NEAR(blk.target[0], 21, 1e-5);
    CHECK_NEAR(blk.target[1], 6, 1e-5);
    CHECK(parse("G90") == STATUS_OK);
    /* inches */
    CHECK(parse("G20G0X1") == STATUS_OK);
    CHECK_NEAR(blk.target[0], 25.4, 1e-4);
    CHECK(parse("G21") == STATUS_OK);
    /* G92: work coordinates shift, machine targets follow */
    CHECK(parse("G92X0Y0") == STATUS_OK && blk.action == ACT_NONE);
    CHECK(parse("G0X10") == STATUS_OK);
    CHECK_NEAR(blk.target[0], 35.4, 1e-4);
    /* G53 moves in machine coordinates */
    CHECK(parse("G53G0X1Y1") == STATUS_OK);
    CHECK_NEAR(blk.target[0], 1, 1e-6);
    /* dwell, G28, line numbers, comments already stripped */
    CHECK(parse("G4P0.5") == STATUS_OK && blk.dwell && blk.dwell_s == 0.5f && blk.action == ACT_NONE);
    CHECK_NEAR(blk.dwell_s, 0.5, 1e-6);
    CHECK(parse("N120G28") == STATUS_OK && blk.action == ACT_G28 && !blk.has_via);
    CHECK(parse("G28X5") == STATUS_OK && blk.has_via);
    CHECK(parse("M17") == STATUS_OK && blk.motors == MOTORS_ON);
    CHECK(parse("M18") == STATUS_OK && blk.motors == MOTORS_OFF);
    CHECK(parse("M84") == STATUS_OK && blk.motors == MOTORS_OFF);
    CHECK(parse("G17G94G54") == STATUS_OK);
    CHECK(parse("M2") == STATUS_OK && blk.program_end);
    CHECK(st.motion == MOTION_G1 && !st.incremental);
    CHECK(parse("") == STATUS_OK && blk.action == ACT_NONE);
    CHECK(parse("G1") == STATUS_OK && blk.action == ACT_NONE); /* mode only */
}

void test_gcode_errors(void)
{
    gc_init(&st);
    CHECK(parse("G1X1") == ERR_UNDEFINED_FEED);
    CHECK(parse("X") == ERR_BAD_NUMBER);
    CHECK(parse("1") == ERR_EXPECTED_LETTER);
    CHECK(parse("G1X1.2.3") == ERR_EXPECTED_LETTER);
    CHECK(parse("G0X1X2") == ERR_WORD_REPEATED);
    /* GRBL's order: a second axis command (G0-G3, G10 G28 G30 G92) is 24
     * before the group's 21; G80 is no axis command */
    CHECK(parse("G0G1X1") == ERR_AXIS_COMMAND_CONFLICT);
    CHECK(parse("G92G1X1") == ERR_AXIS_COMMAND_CONFLICT);
    CHECK(parse("G80G0X1") == ERR_MODAL_CONFLICT);
    CHECK(parse("G0G80") == ERR_MODAL_CONFLICT);
    CHECK(parse("G80G92X0") == ERR_AXIS_WORDS_UNUSED);
    CHECK(parse("G4G53P1") == ERR_MODAL_CONFLICT);
    /* a fraction on a whole number GRBL knows is 23, on any other 20 */
    CHECK(parse("G59.1") == ERR_NOT_INTEGER);
    CHECK(parse("G28.2") == ERR_UNSUPPORTED);
    CHECK(parse("G61.1") == ERR_UNSUPPORTED);
    CHECK(parse("M3.5") == ERR_NOT_INTEGER);
    CHECK(parse("M8M9") == ERR_MODAL_CONFLICT);
    CHECK(parse("M7") == ERR_UNSUPPORTED);
    CHECK(parse("M3M5") == ERR_MODAL_CONFLICT);
    CHECK(parse("G20G21") == ERR_MODAL_CONFLICT);
    CHECK(parse("G5") == ERR_UNSUPPORTED);
    CHECK(parse("G1.5") == ERR_NOT_INTEGER);
    CHECK(parse("G38.2") == ERR_UNSUPPORTED);
    CHECK(parse("M6") == ERR_UNSUPPORTED);
    CHECK(parse("T1") == STATUS_OK);
    CHECK(parse("T256") == ERR_TOOL_NUMBER);
    CHECK(parse("T-300") == ERR_NEGATIVE); /* GRBL: the range check passes it, then the sign */
    /* GRBL's range: N up to 10,000,000; the block carries the whole part */
    CHECK(parse("N10000001G0X1") == ERR_LINE_NUMBER);
    CHECK(parse("N10000000G0X1") == STATUS_OK && blk.line == 10000000);
    CHECK(parse("N-1G0X1") == ERR_NEGATIVE);
    CHECK(parse("N42.7G0X2") == STATUS_OK && blk.line == 42);
    CHECK(parse("G0X3") == STATUS_OK && blk.line == 0);
    CHECK(parse("M0M2") == ERR_MODAL_CONFLICT);
    CHECK(parse("G53G2X1I1") == ERR_G53_MOTION);
    CHECK(parse("G53G92X1") == ERR_MODAL_CONFLICT);
    CHECK(parse("G18G2X1I1F100") == ERR_UNSUPPORTED);
    CHECK(parse("G17G40G49G61G91.1G94G54M9") == STATUS_OK);
    CHECK(parse("/G0X1") == STATUS_OK);
    CHECK(parse("G80X1") == ERR_AXIS_WORDS_UNUSED);
    CHECK(parse("G0") == STATUS_OK);
    CHECK(parse("A5") == ERR_UNSUPPORTED);
    CHECK(parse("G4") == ERR_VALUE_WORD_MISSING);
    CHECK(parse("G4P-1") == ERR_NEGATIVE);
    CHECK(parse("G1F-5") == ERR_NEGATIVE);
    CHECK(parse("G0X1P1") == ERR_UNUSED_WORDS);
    CHECK(parse("G0X1I1") == ERR_UNUSED_WORDS);
    CHECK(parse("G92") == ERR_NO_AXIS_WORDS);
    /* a dwell and a motion on one line: the dwell, then the motion (GRBL's
     * order of execution); a G1 there still needs a feed */
    gc_state_t saved = st;
    CHECK(parse("G4P1X1") == STATUS_OK && blk.dwell && blk.dwell_s == 1.0f && blk.action == ACT_RAPID);
    CHECK(parse("G4P1G1X2") == ERR_UNDEFINED_FEED);
    CHECK(parse("G4P1G1X2F100") == STATUS_OK && blk.dwell && blk.action == ACT_LINE && blk.target[0] == 2.0f);
    CHECK(parse("G4P1Z-1") == STATUS_OK && blk.dwell && blk.pen == PEN_DOWN);
    CHECK(parse("G4P1G0") == STATUS_OK && blk.dwell && st.motion == MOTION_G0);
    CHECK(parse("G4G28") == ERR_MODAL_CONFLICT);
    /* G-0 is G0 to GRBL (-0's whole part and fraction are 0); G-1 is not */
    CHECK(parse("G1F100") == STATUS_OK && st.motion == MOTION_G1);
    CHECK(parse("G-0X3") == STATUS_OK && st.motion == MOTION_G0 && blk.action == ACT_RAPID);
    CHECK(parse("G-1X3") == ERR_UNSUPPORTED);
    CHECK(parse("G-0.04") == ERR_NOT_INTEGER);
    st = saved;
    CHECK(parse("M300") == ERR_VALUE_WORD_MISSING);
    CHECK(parse("G0X1234567890") == ERR_BAD_NUMBER);
    CHECK(parse("G0X200000") == ERR_INVALID_TARGET);
    CHECK(parse("G1X1F1e5") == ERR_EXPECTED_LETTER); /* no exponents in G-code: 'e' is not a word here */
    CHECK(parse("N-1") == ERR_NEGATIVE);
    /* a failed line changes nothing, with G or M words (the whole state
     * copied) or without (feed, z and pos put back) */
    gc_state_t before = st;
    CHECK(parse("G91G1X1") == ERR_UNDEFINED_FEED);
    CHECK(memcmp(&before, &st, sizeof(st)) == 0);
    CHECK(parse("X3Y4Z-1F700I1") == ERR_UNUSED_WORDS);
    CHECK(memcmp(&before, &st, sizeof(st)) == 0);
    CHECK(parse("F700Z-1X200000") == ERR_INVALID_TARGET);
    CHECK(memcmp(&before, &st, sizeof(st)) == 0);
    /* and a line the caller refuses after it parsed (soft limits) is put
     * back whole by gc_undo */
    CHECK(parse("X3Y4Z-1F700") == STATUS_OK && memcmp(&before, &st, sizeof(st)) != 0);
    gc_undo(&st, &undo, &blk);
    CHECK(memcmp(&before, &st, sizeof(st)) == 0);
    CHECK(parse("G91G1X1Y2F800M3") == STATUS_OK && st.incremental);
    gc_undo(&st, &undo, &blk);
    CHECK(memcmp(&before, &st, sizeof(st)) == 0);
    /* jog rules (a jog parses a copy: it changes no modal state) */
    gc_block_t j;
    gc_state_t after = st;
    CHECK(gc_parse("G91X10F1000", &after, &j, 1, &undo) == STATUS_OK && j.action == ACT_LINE);
    /* GRBL: the missing F first (22), then the checks of any line, then
     * words it leaves unused (36: S and T too), then a command a jog may
     * not have (16) */
    CHECK(gc_parse("X10", &after, &j, 1, &undo) == ERR_UNDEFINED_FEED);
    CHECK(gc_parse("G4P1", &after, &j, 1, &undo) == ERR_UNDEFINED_FEED);
    CHECK(gc_parse("G91X-1", &after, &j, 1, &undo) == ERR_UNDEFINED_FEED);
    CHECK(gc_parse("G4P1F100", &after, &j, 1, &undo) == ERR_INVALID_JOG);
    CHECK(gc_parse("G4X1F100", &after, &j, 1, &undo) == ERR_VALUE_WORD_MISSING);
    CHECK(gc_parse("G91X1F100S100", &after, &j, 1, &undo) == ERR_UNUSED_WORDS);
    CHECK(gc_parse("G1X1F100S1", &after, &j, 1, &undo) == ERR_UNUSED_WORDS);
    CHECK(gc_parse("X1F100T1", &after, &j, 1, &undo) == ERR_UNUSED_WORDS);
    CHECK(gc_parse("G0X10F100", &after, &j, 1, &undo) == ERR_INVALID_JOG);
    CHECK(gc_parse("G1X10F100", &after, &j, 1, &undo) == ERR_INVALID_JOG);
    CHECK(gc_parse("M3X1F100", &after, &j, 1, &undo) == ERR_INVALID_JOG);
    CHECK(gc_parse("F100", &after, &j, 1, &undo) == ERR_INVALID_JOG);
    CHECK(gc_parse("G0G1X1F100", &after, &j, 1, &undo) == ERR_AXIS_COMMAND_CONFLICT);
    CHECK(gc_parse("G5X1F100", &after, &j, 1, &undo) == ERR_UNSUPPORTED);
    CHECK(gc_parse("X1A1F100", &after, &j, 1, &undo) == ERR_UNSUPPORTED);
    CHECK(gc_parse("G53G2X1I1F100", &after, &j, 1, &undo) == ERR_G53_MOTION);
    CHECK(gc_parse("N10000001X1F100", &after, &j, 1, &undo) == ERR_LINE_NUMBER);
    CHECK(gc_parse("X1F0", &after, &j, 1, &undo) == ERR_UNDEFINED_FEED);
    /* Z is jogged (the pen, as a G1's Z): with X and Y or alone */
    after = st;
    after.z = 0.0f;
    CHECK(gc_parse("G91X1Z1F100", &after, &j, 1, &undo) == STATUS_OK && j.action == ACT_LINE &&
          j.pen == PEN_UP && after.z == 1.0f && j.feed == 100.0f);
    after = st;
    CHECK(gc_parse("G90Z-1F100", &after, &j, 1, &undo) == STATUS_OK && j.pen == PEN_DOWN);
    /* a jog is a G1 at F whatever the modal state says (G0 here) */
    after = st;
    after.motion = MOTION_G0;
    CHECK(gc_parse("X5F300", &after, &j, 1, &undo) == STATUS_OK && j.action == ACT_LINE && j.feed == 300.0f);
}

void test_gcode_grbl_state(void)
{
    gc_init(&st);
    /* an explicit G1 needs a feed even without axis words */
    CHECK(parse("G01S1") == ERR_UNDEFINED_FEED);
    /* S is kept for $G, M8/M9 too; M2 clears the coolant */
    CHECK(parse("S250") == STATUS_OK && st.spindle == 250.0f);
    CHECK(parse("M8") == STATUS_OK && st.coolant == 1);
    CHECK(parse("M2") == STATUS_OK && st.coolant == 0 && st.spindle == 250.0f);
    /* M0 pauses, M1 does not (GRBL 1.1h has no optional stop) */
    CHECK(parse("M0") == STATUS_OK && blk.pause);
    CHECK(parse("M1") == STATUS_OK && !blk.pause);
    /* G92.1 with axis words: a motion, its target in the frame before the line */
    gc_init(&st);
    CHECK(parse("G0X40Y40") == STATUS_OK);
    CHECK(parse("G92.1X0Y0") == STATUS_OK && blk.action == ACT_RAPID);
    CHECK(blk.target[0] == 0.0f && blk.target[1] == 0.0f);
    CHECK(parse("G92X0Y0Z0") == STATUS_OK && gc_wco(&st, 2) == 0.0f); /* Z: 0 at power-up */
    CHECK(parse("G0X40Y40") == STATUS_OK && parse("G92X0Y0") == STATUS_OK && gc_wco(&st, 0) == 40.0f);
    CHECK(parse("G92.1G0X1") == STATUS_OK && blk.target[0] == 41.0f && gc_wco(&st, 0) == 0.0f);
    /* K in G17 arcs: ignored as GRBL does (no Z arcs); elsewhere unused */
    gc_init(&st);
    CHECK(parse("G0X10Y10") == STATUS_OK);
    CHECK(parse("G2X12Y10I1K1F500") == STATUS_OK && blk.action == ACT_ARC);
    CHECK(parse("G0X1K1") == ERR_UNUSED_WORDS);
    /* G10 L20 P0/P1 on every build (the 328P stores G54 only) */
    gc_init(&st);
    CHECK(parse("G0X30Y20") == STATUS_OK);
    CHECK(parse("G10L20P1X0Y0") == STATUS_OK && blk.store_slot == 1);
    CHECK(gc_wco(&st, 0) == 30.0f && gc_wco(&st, 1) == 20.0f);
    CHECK(parse("G10L20P0X5") == STATUS_OK && gc_wco(&st, 0) == 25.0f);
    CHECK(parse("G10L2P1X1Y2") == STATUS_OK && gc_wco(&st, 1) == 2.0f);
    CHECK(parse("G10L20P7X0") == ERR_UNSUPPORTED_COORD);
    CHECK(parse("G10L3P1X0") == ERR_UNSUPPORTED);
}

void test_gcode_arcs(void)
{
    gc_init(&st);
    CHECK(parse("G0X10Y10") == STATUS_OK);
    CHECK(parse("G2X20Y10I5J0F1000") == STATUS_OK && blk.action == ACT_ARC && blk.clockwise);
    CHECK_NEAR(blk.center[0], 15, 1e-5);
    CHECK_NEAR(blk.center[1], 10, 1e-5);
    /* R form: a quarter circle of radius 10, centre on the right side for G2 */
    CHECK(parse("G0X0Y0") == STATUS_OK);
    CHECK(parse("G2X10Y10R10F1000") == STATUS_OK);
    CHECK_NEAR(blk.center[0], 10, 1e-4);
    CHECK_NEAR(blk.center[1], 0, 1e-4);
    CHECK(parse("G0X0Y0") == STATUS_OK);
    CHECK(parse("G3X10Y10R10") == STATUS_OK);
    CHECK_NEAR(blk.center[0], 0, 1e-4);
    CHECK_NEAR(blk.center[1], 10, 1e-4);
    /* errors */
    CHECK(parse("G2X5Y5") == ERR_NO_OFFSETS);
    CHECK(parse("G2I5") == ERR_NO_AXIS_WORDS);
    CHECK(parse("G2X50Y0R1") == ERR_ARC_RADIUS); /* GRBL: radius too small for the chord */          /* radius too small for the chord */
    CHECK(parse("G2X20Y0I5J0") == ERR_INVALID_TARGET);        /* end not on the circle */
    CHECK(parse("G2X10Y10R10I1") == ERR_UNUSED_WORDS);
    CHECK(parse("G2X10Y10R-999999999") == ERR_INVALID_TARGET); /* found by the fuzzer */
}

void test_gcode_pen(void)
{
    gc_init(&st);
    CHECK(parse("M3") == STATUS_OK && blk.pen == PEN_DOWN);
    CHECK(parse("M5") == STATUS_OK && blk.pen == PEN_UP);
    CHECK(parse("M300S30") == STATUS_OK && blk.pen == PEN_DOWN);
    CHECK(parse("M300S50") == STATUS_OK && blk.pen == PEN_UP);
    CHECK(parse("G1Z-1F100") == STATUS_OK && blk.pen == PEN_DOWN && blk.action == ACT_NONE);
    CHECK(parse("G0Z5") == STATUS_OK && blk.pen == PEN_UP);
    CHECK(parse("G0Z0") == STATUS_OK && blk.pen == PEN_DOWN);
    CHECK(parse("G0X1Z2") == STATUS_OK && blk.pen == PEN_UP && blk.action == ACT_RAPID);
    CHECK(parse("M5Z-1") == STATUS_OK && blk.pen == PEN_UP); /* the explicit M word wins */
    CHECK(parse("G0X2") == STATUS_OK && blk.pen == PEN_KEEP);
    /* offsets never move the pen, and cannot flip the threshold (machine Z) */
    CHECK(parse("G0Z5") == STATUS_OK && blk.pen == PEN_UP);
    CHECK(parse("G92X0Y0Z0") == STATUS_OK && blk.pen == PEN_KEEP && blk.wco_changed);
    CHECK(parse("G0Z0") == STATUS_OK && blk.pen == PEN_UP); /* work Z 0 is machine Z 5 */
    CHECK(parse("G53G0X30Y30Z0") == STATUS_OK && blk.pen == PEN_KEEP);
    CHECK(parse("G92.1") == STATUS_OK && blk.pen == PEN_KEEP && blk.wco_changed);
    CHECK(parse("G0Z0") == STATUS_OK && blk.pen == PEN_DOWN);
    CHECK(parse("G28Z5") == STATUS_OK && blk.pen == PEN_KEEP);
}

/* what machine.c does with a block's store request */
static void store(void)
{
    if (blk.store_slot)
        coord_save((uint8_t)(blk.store_slot - 1), blk.store);
}

/* G54-G59 with G10 L2/L20, G28/G30 and their .1, as GRBL 1.1 */
void test_gcode_coords(void)
{
    host_store_reset();
    gc_init(&st);
    CHECK(parse("G10L2P2X10Y20Z1") == STATUS_OK && blk.store_slot == 2 && !blk.wco_changed);
    store();
    CHECK_NEAR(blk.store[0], 10, 1e-6);
    CHECK(parse("G55") == STATUS_OK && st.coord == 1);
    CHECK_NEAR(gc_wco(&st, 0), 10, 1e-6);
    CHECK(parse("G0X5Y5") == STATUS_OK);
    CHECK_NEAR(blk.target[0], 15, 1e-5);
    CHECK_NEAR(blk.target[1], 25, 1e-5);
    /* the Z offset never flips the pen: work Z 0 is machine Z 1, above the threshold */
    CHECK(parse("G0Z0") == STATUS_OK && blk.pen == PEN_UP);
    /* L20: the offset that makes here read X1 (G92 counted) */
    CHECK(parse("G92X0") == STATUS_OK);
    CHECK(parse("G10L20P0X1") == STATUS_OK && blk.store_slot == 2 && blk.wco_changed);
    store();
    CHECK_NEAR(gc_wco(&st, 0), 14, 1e-5); /* machine 15 reads 1 */
    CHECK(parse("G92.1") == STATUS_OK);
    CHECK(parse("G10L20P1X0Y0") == STATUS_OK && blk.store_slot == 1 && !blk.wco_changed);
    store();
    CHECK(parse("G54") == STATUS_OK);
    CHECK_NEAR(gc_wco(&st, 0), 15, 1e-5);
    CHECK_NEAR(gc_wco(&st, 1), 25, 1e-5);
    /* errors: GRBL's numbers */
    CHECK(parse("G10L2X1") == ERR_VALUE_WORD_MISSING);
    CHECK(parse("G10P1X1") == ERR_VALUE_WORD_MISSING);
    CHECK(parse("G10L2P7X1") == ERR_UNSUPPORTED_COORD);
    CHECK(parse("G10L3P1X1") == ERR_UNSUPPORTED);
    CHECK(parse("G10L2P1R1X1") == ERR_UNSUPPORTED);
    CHECK(parse("G10L2P1") == ERR_NO_AXIS_WORDS);
    CHECK(parse("G1G10L2P1X1") == ERR_AXIS_COMMAND_CONFLICT);
    CHECK(parse("G54G55") == ERR_MODAL_CONFLICT);
    CHECK(parse("G0L2X1") == ERR_UNUSED_WORDS);
    host_store_corrupt(3);
    CHECK(parse("G57") == ERR_EEPROM_READ && st.coord == 0);
    CHECK(parse("G57") == STATUS_OK && st.coord == 3); /* rewritten as zeros */
    CHECK(parse("G54") == STATUS_OK);
    /* G28.1 stores where the machine is; G28 goes there (only the named axes
     * when axis words are given, as GRBL 1.1) */
    CHECK(parse("G53G0X30Y40") == STATUS_OK);
    CHECK(parse("G28.1") == STATUS_OK && blk.store_slot == GC_SLOT_G28 + 1 && blk.action == ACT_NONE);
    store();
    CHECK(parse("G30.1") == STATUS_OK && blk.store_slot == GC_SLOT_G30 + 1);
    store();
    CHECK(parse("G53G0X1Y2") == STATUS_OK);
    CHECK(parse("G28") == STATUS_OK && blk.action == ACT_G28 && !blk.has_via);
    CHECK_NEAR(blk.target[0], 30, 1e-5);
    CHECK_NEAR(blk.target[1], 40, 1e-5);
    CHECK(parse("G53G0X1Y2") == STATUS_OK);
    CHECK(parse("G28G91X0") == STATUS_OK && blk.has_via);
    CHECK_NEAR(blk.target[0], 30, 1e-5);
    CHECK_NEAR(blk.target[1], 2, 1e-5); /* Y not named: stays */
    CHECK(parse("G90G30") == STATUS_OK);
    CHECK_NEAR(blk.target[0], 30, 1e-5);
    /* program end: back to G54 */
    CHECK(parse("G55") == STATUS_OK && parse("M2") == STATUS_OK && st.coord == 0);
}

/* G93: F per line, 1/min, not scaled by G20; G94 afterwards needs an F */
void test_gcode_inverse_time(void)
{
    host_store_reset();
    gc_init(&st);
    CHECK(parse("G93G1X10F2") == STATUS_OK && blk.inverse_time && blk.feed == 2.0f);
    CHECK(parse("X20") == ERR_UNDEFINED_FEED);
    CHECK(parse("G0X0") == STATUS_OK);
    CHECK(parse("G20G1X1F3") == STATUS_OK && blk.feed == 3.0f);
    CHECK(parse("G21G94G1X5") == ERR_UNDEFINED_FEED);
    CHECK(parse("G21G94G1X5F100") == STATUS_OK && !blk.inverse_time);
    CHECK(parse("G93G94") == ERR_MODAL_CONFLICT);
}
