/* sere harness — one function per subcommand. Each parses its own options (argv[0] is the
 * subcommand name), prints one clear line to stderr and returns non-zero on bad input.
 * They return int, not sere_status: the value is the process's exit code (0, 1 failed, 2 usage). */
#pragma once

int sere_cmd_model( int argc, char** argv );
int sere_cmd_run( int argc, char** argv );
int sere_cmd_osmosis( int argc, char** argv );
int sere_cmd_table1( int argc, char** argv );
int sere_cmd_topo( int argc, char** argv );
int sere_cmd_season( int argc, char** argv );
int sere_cmd_wilt( int argc, char** argv );
int sere_cmd_litter( int argc, char** argv );
