/* checkpoint.c -- being written (issue 6) */
typedef int ss_checkpoint_placeholder;
