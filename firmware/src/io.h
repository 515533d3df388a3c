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
/* two pins on the same port (a constant expression: the compiler folds it) */
#define IO_SAME_PORT(a, b) (&IO_PORT(a) == &IO_PORT(b))

#endif
