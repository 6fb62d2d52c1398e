/* arena.h - bump allocator that owns everything one compilation builds. */
#ifndef MECHC_ARENA_H
#define MECHC_ARENA_H

#include <stddef.h>

typedef struct ArenaBlock ArenaBlock;

/* Memory is released all at once by arena_free; nothing is freed singly.
   Allocation failure aborts: mechc cannot continue without memory and the
   input limits keep a valid run far below what the machine has. */
typedef struct Arena {
    ArenaBlock *head;
    size_t used_total;      /* bytes handed out, for statistics */
} Arena;

void  arena_init(Arena *arena);
void  arena_free(Arena *arena);
void *arena_alloc(Arena *arena, size_t size);            /* zero-filled */
void *arena_alloc_array(Arena *arena, size_t count, size_t size);
char *arena_strdup(Arena *arena, const char *s);
char *arena_strndup(Arena *arena, const char *s, size_t n);

/* Heap helpers with the same abort-on-failure policy, for growable arrays
   that outlive no owner (each has exactly one free site). */
void *xmalloc(size_t size);
void *xcalloc(size_t count, size_t size);
void *xrealloc(void *p, size_t count, size_t size);

#endif
