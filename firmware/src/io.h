/* Pin helpers for the board headers: a pin is written as "PORT LETTER, BIT"
 * (e.g. `#define X_STEP D, 2`), and these turn it into its registers, so a
 * board header is the only place a pin is named. Safe to include on the host
 * (the registers are only expanded where they are used). */
#ifndef IO_H
#define IO_H

#define IO_PORT(...) IO_PORT_(__VA_ARGS__)
#define IO_PORT_(p, b) PORT##p
#define IO_DDR(...) IO_DDR_(__VA_ARGS__)
#define IO_DDR_(p, b) DDR##p
#define IO_PINREG(...) IO_PINREG_(__VA_ARGS__)
#define IO_PINREG_(p, b) PIN##p
#define IO_BIT(...) IO_BIT_(__VA_ARGS__)
#define IO_BIT_(p, b) (b)
#define IO_MASK(...) ((uint8_t)(1u << IO_BIT(__VA_ARGS__)))

/* Output high/low and input level; each is one instruction for these ports
 * (sbi/cbi/sbic) or a short read-modify-write on the 2560's upper ports. */
#define IO_OUTPUT(...) (IO_DDR(__VA_ARGS__) |= IO_MASK(__VA_ARGS__))
#define IO_INPUT_PULLUP(...) (IO_DDR(__VA_ARGS__) &= (uint8_t)~IO_MASK(__VA_ARGS__), IO_PORT(__VA_ARGS__) |= IO_MASK(__VA_ARGS__))
#define IO_HIGH(...) (IO_PORT(__VA_ARGS__) |= IO_MASK(__VA_ARGS__))
#define IO_LOW(...) (IO_PORT(__VA_ARGS__) &= (uint8_t)~IO_MASK(__VA_ARGS__))
#define IO_SET(pin, on) ((on) ? IO_HIGH(pin) : IO_LOW(pin))
#define IO_READ(...) ((IO_PINREG(__VA_ARGS__) & IO_MASK(__VA_ARGS__)) != 0)
/* writing a 1 to PINx toggles PORTx: one cycle, and atomic */
#define IO_TOGGLE(...) (IO_PINREG(__VA_ARGS__) = IO_MASK(__VA_ARGS__))
/* two pins on the same port: a number per port letter, so that the
 * preprocessor can test it too (#if IO_SAME_PORT(X_STEP, Y_STEP)) */
#define IO_PORT_NUM(...) IO_PORT_NUM_(__VA_ARGS__)
#define IO_PORT_NUM_(p, b) IO_PORT_NUM_##p
#define IO_PORT_NUM_A 1
#define IO_PORT_NUM_B 2
#define IO_PORT_NUM_C 3
#define IO_PORT_NUM_D 4
#define IO_PORT_NUM_E 5
#define IO_PORT_NUM_F 6
#define IO_PORT_NUM_G 7
#define IO_PORT_NUM_H 8
#define IO_PORT_NUM_J 9
#define IO_PORT_NUM_K 10
#define IO_PORT_NUM_L 11
#define IO_SAME_PORT(a, b) (IO_PORT_NUM(a) == IO_PORT_NUM(b))

#endif
