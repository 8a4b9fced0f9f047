/* sere harness — Thinning: the vein strokes to one-pixel skeletons (Zhang-Suen). */
#include "read/leafimage_shared.h"

#include <stdlib.h>
#include <string.h>

void leafimage_thin( uint8_t* m, int w, int h, int32_t* live, int32_t count )
{
	/* P2..P9 clockwise from north, P2 repeated to close the ring */
	static const int ring[9][2] = { { 0, -1 }, { 1, -1 }, { 1, 0 },	  { 1, 1 }, { 0, 1 },
									{ -1, 1 }, { -1, 0 }, { -1, -1 }, { 0, -1 } };
	int changed = 1;
	while ( changed )
	{
		changed = 0;
		for ( int pass = 0; pass < 2; ++pass )
		{
			for ( int32_t k = 0; k < count; ++k )
			{
				int x = live[k] % w, y = live[k] / w;
				int p[9];
				for ( int j = 0; j < 9; ++j )
				{
					int qx = x + ring[j][0], qy = y + ring[j][1];
					p[j] = qx >= 0 && qy >= 0 && qx < w && qy < h && m[qy * w + qx] != 0;
				}
				int neighbors = 0, transitions = 0;
				for ( int j = 0; j < 8; ++j )
				{
					neighbors += p[j];
					transitions += !p[j] && p[j + 1];
				}
				int c = pass == 0 ? !( p[0] && p[2] && p[4] ) : !( p[0] && p[2] && p[6] );
				int e = pass == 0 ? !( p[2] && p[4] && p[6] ) : !( p[0] && p[4] && p[6] );
				if ( neighbors >= 2 && neighbors <= 6 && transitions == 1 && c && e )
				{
					m[live[k]] = 2;
				}
			}
			int32_t kept = 0;
			for ( int32_t k = 0; k < count; ++k )
			{
				if ( m[live[k]] == 2 )
				{
					m[live[k]] = 0;
					changed = 1;
				}
				else
				{
					live[kept++] = live[k];
				}
			}
			count = kept;
		}
	}
}
