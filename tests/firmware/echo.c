/* echo.c: reads lines from UARTHS's receiver and answers each, for the board model's
 * --uart-input and --expect. It echoes what it receives, as a terminal program does, and
 * ends at a line "quit". */
#include <stdio.h>
#include <string.h>

#include "drivers.h"
#include "k210.h"

#define CONSOLE_BAUD 115200u
#define LINE_MAX 80

/* Reads one line into `line` (without its ending; CR, LF or both end it), echoing it. */
static size_t read_line(char *line, size_t size)
{
    size_t length = 0;
    for (;;) {
        int c = uarths_getc();
        if (c == '\r' || c == '\n') {
            if (length == 0 && c == '\n')
                continue;          /* the LF of a CR LF pair */
            break;
        }
        uarths_putc((char)c);
        if (length + 1 < size)
            line[length++] = (char)c;
    }
    line[length] = '\0';
    printf("\n");
    return length;
}

int main(void)
{
    clock_enable(CLOCK_FPIOA);
    fpioa_set_function(PAD_UARTHS_RX, FUNC_UARTHS_RX);
    fpioa_set_function(PAD_UARTHS_TX, FUNC_UARTHS_TX);
    uarths_init(CONSOLE_BAUD);

    char line[LINE_MAX];
    printf("name? ");
    fflush(stdout);
    read_line(line, sizeof line);
    printf("hello, %s!\n", line);
    for (unsigned count = 1;; count++) {
        printf("> ");
        fflush(stdout);
        size_t length = read_line(line, sizeof line);
        if (strcmp(line, "quit") == 0)
            break;
        printf("line %u: %zu characters, reversed: ", count, length);
        for (size_t i = length; i > 0; i--)
            uarths_putc(line[i - 1]);
        printf("\n");
    }
    printf("bye\n");
    return 0;
}
