/* The number parsers of the command-line programs (clwhitted and the tools): the whole of
 * s is a decimal integer (a number) within lo..hi. They return 0, or -1 and print nothing:
 * each program words its own message. */
#ifndef CW_CLI_NUM_H
#define CW_CLI_NUM_H

int cli_parse_long(const char *s, long lo, long hi, long *out);
int cli_parse_double(const char *s, double lo, double hi, double *out);

#endif
