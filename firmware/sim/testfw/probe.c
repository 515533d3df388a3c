/* Test firmware for plotsim: known pin activity at power-up, then a tiny
 * serial command set. Pins as on the CNC shield (DESIGN.md).
 *
 * Power-up: servo pulse 1000 us (pen up), 2000 us (pen down); 800 X steps
 * with dir low (positive, as GRBL), then 400 Y steps with dir low, 10 us high / 90 us low
 * (10 kHz); servo pulse 1000 us (pen up). From (0,0) at 80 steps/mm that is
 * one stroke (0,0) -> (10,0) -> (10,5).
 *
 * Serial (115200 8N1), one byte commands, anything else is echoed:
 *   ?        state line "S<stop><pause><resume><xlimit><ylimit>\n", 1 = active (low)
 *   X x Y y  one step +X, -X, +Y, -Y, then the state line
 *   P        one X step pulse of two cycles (too short), then the state line
 *   Z        direction change in the same write as the step edge, then the state line
 *   D E      drivers disabled / enabled, then the state line
 *   W        add one to EEPROM byte 0, answer "W" and its new value in two hex digits
 *   R        watchdog reset (the power-up drawing runs again)
 *   F        step X at 30 kHz forever from a timer interrupt, reversing every 4000 steps
 * The stop LED (A3) follows the stop button. */
#include <avr/eeprom.h>
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/wdt.h>
#include <util/delay.h>

#define STEP_X _BV(PD2)
#define STEP_Y _BV(PD3)
#define DIR_X _BV(PD5)
#define DIR_Y _BV(PD6)
#define ENABLE _BV(PB0)
#define LIMIT_X _BV(PB1)
#define LIMIT_Y _BV(PB2)
#define SERVO _BV(PB3)
#define BTN_STOP _BV(PC0)
#define BTN_PAUSE _BV(PC1)
#define BTN_RESUME _BV(PC2)
#define LED _BV(PC3)

static void put(char c)
{
	while (!(UCSR0A & _BV(UDRE0)))
		;
	UDR0 = c;
}

static char active(volatile uint8_t *pin, uint8_t mask)
{
	return (*pin & mask) ? '0' : '1';
}

static void state_line(void)
{
	put('S');
	put(active(&PINC, BTN_STOP));
	put(active(&PINC, BTN_PAUSE));
	put(active(&PINC, BTN_RESUME));
	put(active(&PINB, LIMIT_X));
	put(active(&PINB, LIMIT_Y));
	put('\n');
}

static void step(uint8_t step_bit, uint8_t dir_bit, uint8_t positive)
{
	if (positive) /* GRBL's convention: LOW is positive */
		PORTD &= (uint8_t)~dir_bit;
	else
		PORTD |= dir_bit;
	_delay_us(5);
	PORTD |= step_bit;
	_delay_us(10);
	PORTD &= (uint8_t)~step_bit;
	_delay_us(90);
}

static void servo_gap(void)
{
	_delay_ms(18);
}

static void power_up_moves(void)
{
	PORTB |= SERVO;
	_delay_us(1000);
	PORTB &= (uint8_t)~SERVO;
	servo_gap();
	PORTB |= SERVO;
	_delay_us(2000);
	PORTB &= (uint8_t)~SERVO;
	servo_gap();
	for (uint16_t i = 0; i < 800; i++)
		step(STEP_X, DIR_X, 1);
	for (uint16_t i = 0; i < 400; i++)
		step(STEP_Y, DIR_Y, 1);
	PORTB |= SERVO;
	_delay_us(1000);
	PORTB &= (uint8_t)~SERVO;
	servo_gap();
}

static volatile uint16_t fast_count;

ISR(TIMER1_COMPA_vect)
{
	PORTD |= STEP_X;
	_delay_us(2);
	PORTD &= (uint8_t)~STEP_X;
	if (++fast_count == 4000) {
		fast_count = 0;
		PORTD ^= DIR_X;
	}
}

static void start_fast(void)
{
	OCR1A = F_CPU / 30000 - 1; /* non-zero before the interrupt is enabled */
	TCCR1A = 0;
	TCCR1B = _BV(WGM12) | _BV(CS10);
	TIMSK1 = _BV(OCIE1A);
	sei();
}

static void put_hex(uint8_t v)
{
	static const char digits[] = "0123456789ABCDEF";
	put(digits[v >> 4]);
	put(digits[v & 15]);
}

static void bump_eeprom(void)
{
	uint8_t v = (uint8_t)(eeprom_read_byte((uint8_t *)0) + 1);
	eeprom_write_byte((uint8_t *)0, v);
	put('W');
	put_hex(v);
	put('\n');
}

static void command(char c)
{
	switch (c) {
	case 'X': step(STEP_X, DIR_X, 1); break;
	case 'x': step(STEP_X, DIR_X, 0); break;
	case 'Y': step(STEP_Y, DIR_Y, 1); break;
	case 'y': step(STEP_Y, DIR_Y, 0); break;
	case 'P':
		PORTD |= STEP_X;
		PORTD &= (uint8_t)~STEP_X;
		_delay_us(10);
		break;
	case 'Z':
		PORTD = (uint8_t)((PORTD ^ DIR_X) | STEP_X);
		_delay_us(10);
		PORTD &= (uint8_t)~STEP_X;
		_delay_us(10);
		break;
	case 'D': PORTB |= ENABLE; break;
	case 'E': PORTB &= (uint8_t)~ENABLE; break;
	case 'F': start_fast(); return;
	case 'W': bump_eeprom(); return;
	case 'R':
		wdt_enable(WDTO_15MS);
		for (;;)
			;
	case '?': break;
	default: put(c); return;
	}
	state_line();
}

int main(void)
{
	MCUSR = 0; /* after a watchdog reset the watchdog stays on until cleared */
	wdt_disable();
	DDRD = STEP_X | STEP_Y | DIR_X | DIR_Y;
	DDRB = ENABLE | SERVO;
	PORTB = LIMIT_X | LIMIT_Y;          /* pull-ups; drivers enabled (low) */
	DDRC = LED;
	PORTC = BTN_STOP | BTN_PAUSE | BTN_RESUME;
	UCSR0A = _BV(U2X0);
	UBRR0 = 16;                         /* 115200 with U2X at 16 MHz */
	UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
	UCSR0B = _BV(RXEN0) | _BV(TXEN0);
	power_up_moves();
	for (;;) {
		if (PINC & BTN_STOP)
			PORTC &= (uint8_t)~LED;
		else
			PORTC |= LED;
		if (UCSR0A & _BV(RXC0))
			command((char)UDR0);
	}
}
