/* sere season — private to the cmd_season*.c files: the chain file and the schedule readers
 * (seed 002: Tang, Wu & Fan 2013). */
#pragma once

#include "season/markov.h"

#include <stdint.h>

#define MAX_STATES	   SERE_MARKOV_MAX_STATES
#define MAX_TRANSITION 512
#define MAX_SCHEDULE   4096
#define MAX_DAYS	   100000
#define NAME_SIZE	   32

typedef struct chain_file
{
	int32_t state_count;
	char name[MAX_STATES][NAME_SIZE];
	uint8_t rgb[MAX_STATES][3];
	int32_t level[MAX_STATES];
	int fallen[MAX_STATES];
	double stay[4 * MAX_STATES];
	int32_t transition_count;
	sere_markov_transition transitions[MAX_TRANSITION];
	int32_t initial;
	int have_corners;
	sere_markov_chain chain;
} chain_file;

/* The schedule: days with temperature and humidity, linear in between; labels name seasons. */
typedef struct schedule
{
	int32_t count;
	int32_t day[MAX_SCHEDULE];
	double temperature[MAX_SCHEDULE];
	double humidity[MAX_SCHEDULE];
	char label[MAX_SCHEDULE][NAME_SIZE];
} schedule;

/* Reads a chain file; 0, or -1 after printing "sere season: PATH:LINE: ..." to stderr. */
int season_read_chain( const char* path, chain_file* c );

/* Reads a schedule file; 0, or -1 after printing why. */
int season_read_schedule( const char* path, schedule* s );

/* The temperature t and humidity h of day, linear between the schedule's days. */
void season_weather( const schedule* s, int32_t day, double* t, double* h );
