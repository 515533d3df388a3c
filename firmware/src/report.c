#include "fmt.h"
#include "report.h"
#include "serial.h"
#include "config.h"
#include "settings.h"

void report_pstr(PGM_P s)
{
    char c;
    while ((c = (char)pgm_read_byte(s++)))
        serial_write((uint8_t)c);
}

void report_str(const char *s)
{
    while (*s)
        serial_write((uint8_t)*s++);
}

void report_uint(uint32_t v)
{
    char buf[FMT_MAX];
    fmt_uint(buf, v);
    report_str(buf);
}

void report_fixed(float v, uint8_t decimals)
{
    char buf[FMT_MAX];
    fmt_fixed(buf, v, decimals);
    report_str(buf);
}

void report_xyz(const float *v)
{
    float div = settings.report_inches ? 25.4f : 1.0f; /* $13 */
    for (uint8_t a = 0; a < 3; a++) {
        if (a)
            report_char(',');
        report_fixed(v[a] / div, 3);
    }
}

void report_status_code(uint8_t code)
{
    if (code == 0) {
        RPT("ok\r\n");
        return;
    }
    RPT("error:");
    report_uint(code);
    RPT("\r\n");
}

void report_alarm(uint8_t code)
{
    RPT("ALARM:");
    report_uint(code);
    RPT("\r\n");
}

void report_banner(void) { RPT("\r\n" FW_BANNER "\r\n"); }

void report_msg(PGM_P text)
{
    RPT("[MSG:");
    report_pstr(text);
    RPT("]\r\n");
}

void report_unlock_hint(void) { report_msg(PSTR("'$H'|'$X' to unlock")); }
