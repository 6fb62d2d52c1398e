/* groups.c - the sparse Jacobian's columns in groups that share no row (Curtis, Powell and Reid).
 *
 * One difference of Phi with every column of a group moved at once gives,
 * in each row, the entry of the one column of the group the pattern has
 * there (fd.c): a handful of differences for a chain instead of nq.
 */
#include "groups.h"

#include <stdlib.h>

/* Counting sort of the entries by key (n keys): start (n + 1) and the
   entries in key order. */
static void entries_by(Checker *c, const int *key, int n, int **start, int **ent)
{
    *start = arena_alloc_array(&c->buffers, (size_t)n + 1, sizeof **start);
    *ent = arena_alloc_array(&c->buffers, (size_t)c->nnz + 1, sizeof **ent);
    int *next = xcalloc((size_t)n + 1, sizeof *next);
    for (int e = 0; e < c->nnz; e++)
        (*start)[key[e] + 1]++;
    for (int i = 0; i < n; i++)
        next[i] = (*start)[i + 1] += (*start)[i];
    for (int i = 0; i < n; i++)
        next[i] = (*start)[i];
    for (int e = 0; e < c->nnz; e++)
        (*ent)[next[key[e]]++] = e;
    free(next);
}

/* The column groups: greedy colouring in column order, a column taking the
   first group none of whose columns shares a row with it. */
void check_group_columns(Checker *c)
{
    const MechrtHostJacNz *j = c->jnz[ENGINE_JIT];
    int *row_start, *row_ent;
    entries_by(c, j->jac.row, c->nr, &row_start, &row_ent);
    entries_by(c, j->jac.col, c->nq, &c->col_start, &c->col_ent);
    int *color = xmalloc(((size_t)c->nq + 1) * sizeof *color);
    int *mark = xmalloc(((size_t)c->nq + 1) * sizeof *mark);
    for (int k = 0; k < c->nq; k++)
        color[k] = mark[k] = -1;
    c->ngroups = 0;
    for (int col = 0; col < c->nq; col++) {
        for (int a = c->col_start[col]; a < c->col_start[col + 1]; a++) {
            int r = j->jac.row[c->col_ent[a]];
            for (int b = row_start[r]; b < row_start[r + 1]; b++) {
                int other = j->jac.col[row_ent[b]];
                if (color[other] >= 0)
                    mark[color[other]] = col;
            }
        }
        int g = 0;
        while (g < c->ngroups && mark[g] == col)
            g++;
        color[col] = g;
        c->ngroups += g == c->ngroups;
    }
    c->group_start = arena_alloc_array(&c->buffers, (size_t)c->ngroups + 1, sizeof *c->group_start);
    c->group_cols = arena_alloc_array(&c->buffers, (size_t)c->nq + 1, sizeof *c->group_cols);
    for (int col = 0; col < c->nq; col++)
        c->group_start[color[col] + 1]++;
    for (int g = 0; g < c->ngroups; g++) {
        c->group_start[g + 1] += c->group_start[g];
        mark[g] = c->group_start[g];
    }
    for (int col = 0; col < c->nq; col++)
        c->group_cols[mark[color[col]]++] = col;
    c->ent = arena_alloc_array(&c->buffers, (size_t)c->nr + 1, sizeof *c->ent);
    for (int r = 0; r < c->nr; r++)
        c->ent[r] = -1;
    free(color), free(mark);
}
