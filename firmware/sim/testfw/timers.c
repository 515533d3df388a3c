/* Test firmware for plotsim's simavr timer fixes: each command makes one
 * pulse on PD2 (the X step pin) whose width shows how the timer behaved,
 * then answers on the serial port (115200 8N1).
 *   T  Timer1 preset to 65536-800 while stopped, then started at clk/1: the
 *      overflow interrupt ends the pulse after 800 cycles (50 us).
 *   C  Timer1 in CTC with OCR1A = 0, compare interrupt enabled, then started:
 *      the chip matches at once, the interrupt ends the pulse.
 *   M  Timer1 overflow flag set while its interrupt is disabled, pulse
 *      started, then the interrupt enabled: it fires at once.
 * Answer: the command letter and '\n', or the letter and "!\n" when the
 * interrupt did not come within ~20 ms (the pulse is ended then). */
#include <avr/interrupt.h>
#include <avr/io.h>

#define STEP_X _BV(PD2)

static volatile uint8_t fired;

static void end_pulse(void)
{
	PORTD &= (uint8_t)~STEP_X;
	TCCR1B = 0;
	TIMSK1 = 0;
	fired = 1;
}

ISR(TIMER1_OVF_vect)
{
	end_pulse();
}

ISR(TIMER1_COMPA_vect)
{
	end_pulse();
}

static void put(char c)
{
	while (!(UCSR0A & _BV(UDRE0)))
		;
	UDR0 = c;
}

/* waits for the interrupt for ~20 ms (5 cycles a loop) */
static void finish(char c)
{
	for (uint32_t i = 0; i < 64000 && !fired; i++)
		__asm__ __volatile__("nop");
	put(c);
	if (!fired) {
		end_pulse();
		put('!');
	}
	put('\n');
}

static void preset_while_stopped(void)
{
	TCCR1A = 0;
	TCCR1B = 0;
	TCNT1 = 65536 - 800;
	TIFR1 = 0xFF;
	TIMSK1 = _BV(TOIE1);
	PORTD |= STEP_X;
	TCCR1B = _BV(CS10);
}

static void ctc_zero(void)
{
	TCCR1A = 0;
	TCCR1B = _BV(WGM12);
	TCNT1 = 0;
	OCR1A = 0;
	TIFR1 = 0xFF;
	TIMSK1 = _BV(OCIE1A);
	PORTD |= STEP_X;
	TCCR1B = _BV(WGM12) | _BV(CS10);
}

static void flag_before_enable(void)
{
	TCCR1A = 0;
	TIMSK1 = 0;
	TCNT1 = 0;
	TIFR1 = 0xFF;
	TCCR1B = _BV(CS10);
	while (!(TIFR1 & _BV(TOV1)))
		;
	PORTD |= STEP_X;
	TIMSK1 = _BV(TOIE1);
}

int main(void)
{
	DDRD = STEP_X;
	DDRB = _BV(PB0); /* drivers enabled (low) */
	UCSR0A = _BV(U2X0);
	UBRR0 = 16;
	UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
	UCSR0B = _BV(RXEN0) | _BV(TXEN0);
	sei();
	for (;;) {
		if (!(UCSR0A & _BV(RXC0)))
			continue;
		char c = (char)UDR0;
		fired = 0;
		if (c == 'T')
			preset_while_stopped();
		else if (c == 'C')
			ctc_zero();
		else if (c == 'M')
			flag_before_enable();
		else
			continue;
		finish(c);
	}
}
