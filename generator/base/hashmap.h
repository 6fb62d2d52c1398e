/* hashmap.h - open-addressing maps: string -> int (symbol tables) and u64 -> int (memo tables). */
#ifndef MECHC_HASHMAP_H
#define MECHC_HASHMAP_H

#include <stdbool.h>
#include <stdint.h>

/* Keys are borrowed (must outlive the map); values are ints (indices). */
typedef struct StrMap {
    const char **keys;
    int *values;
    uint32_t cap, count;
} StrMap;

void strmap_init(StrMap *map);
void strmap_free(StrMap *map);
bool strmap_get(const StrMap *map, const char *key, int *value);
void strmap_put(StrMap *map, const char *key, int value);

typedef struct U64Map {
    uint64_t *keys;     /* UINT64_MAX marks an empty slot */
    int32_t *values;
    uint32_t cap, count;
} U64Map;

void u64map_init(U64Map *map);
void u64map_free(U64Map *map);
bool u64map_get(const U64Map *map, uint64_t key, int32_t *value);
void u64map_put(U64Map *map, uint64_t key, int32_t value);

#endif
