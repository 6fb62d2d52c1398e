/* hashmap.c - open addressing with linear probing; tables double at half full. */
#include "hashmap.h"

#include "arena.h"

#include <stdlib.h>
#include <string.h>

static uint32_t hash_string(const char *s)
{
    uint32_t h = 2166136261u;       /* FNV-1a */
    for (; *s; s++) {
        h ^= (unsigned char)*s;
        h *= 16777619u;
    }
    return h;
}

static uint32_t hash_u64(uint64_t k)
{
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdull;
    k ^= k >> 33;
    k *= 0xc4ceb9fe1a85ec53ull;
    k ^= k >> 33;
    return (uint32_t)k;
}

void strmap_init(StrMap *map) { memset(map, 0, sizeof *map); }

void strmap_free(StrMap *map)
{
    free(map->keys);
    free(map->values);
    memset(map, 0, sizeof *map);
}

bool strmap_get(const StrMap *map, const char *key, int *value)
{
    if (!map->cap)
        return false;
    uint32_t mask = map->cap - 1;
    for (uint32_t h = hash_string(key) & mask; map->keys[h]; h = (h + 1) & mask) {
        if (strcmp(map->keys[h], key) == 0) {
            *value = map->values[h];
            return true;
        }
    }
    return false;
}

static void strmap_insert(StrMap *map, const char *key, int value)
{
    uint32_t mask = map->cap - 1;
    uint32_t h = hash_string(key) & mask;
    while (map->keys[h] && strcmp(map->keys[h], key) != 0)
        h = (h + 1) & mask;
    if (!map->keys[h])
        map->count++;
    map->keys[h] = key;
    map->values[h] = value;
}

void strmap_put(StrMap *map, const char *key, int value)
{
    if ((map->count + 1) * 2 > map->cap) {
        StrMap old = *map;
        map->cap = old.cap ? old.cap * 2 : 64;
        map->count = 0;
        map->keys = xcalloc(map->cap, sizeof *map->keys);
        map->values = xcalloc(map->cap, sizeof *map->values);
        for (uint32_t i = 0; i < old.cap; i++)
            if (old.keys[i])
                strmap_insert(map, old.keys[i], old.values[i]);
        free(old.keys);
        free(old.values);
    }
    strmap_insert(map, key, value);
}

void u64map_init(U64Map *map) { memset(map, 0, sizeof *map); }

void u64map_free(U64Map *map)
{
    free(map->keys);
    free(map->values);
    memset(map, 0, sizeof *map);
}

bool u64map_get(const U64Map *map, uint64_t key, int32_t *value)
{
    if (!map->cap)
        return false;
    uint32_t mask = map->cap - 1;
    for (uint32_t h = hash_u64(key) & mask; map->keys[h] != UINT64_MAX; h = (h + 1) & mask) {
        if (map->keys[h] == key) {
            *value = map->values[h];
            return true;
        }
    }
    return false;
}

static void u64map_insert(U64Map *map, uint64_t key, int32_t value)
{
    uint32_t mask = map->cap - 1;
    uint32_t h = hash_u64(key) & mask;
    while (map->keys[h] != UINT64_MAX && map->keys[h] != key)
        h = (h + 1) & mask;
    if (map->keys[h] == UINT64_MAX)
        map->count++;
    map->keys[h] = key;
    map->values[h] = value;
}

void u64map_put(U64Map *map, uint64_t key, int32_t value)
{
    if ((map->count + 1) * 2 > map->cap) {
        U64Map old = *map;
        map->cap = old.cap ? old.cap * 2 : 1024;
        map->count = 0;
        map->keys = xmalloc(map->cap * sizeof *map->keys);
        memset(map->keys, 0xff, map->cap * sizeof *map->keys);
        map->values = xmalloc(map->cap * sizeof *map->values);
        for (uint32_t i = 0; i < old.cap; i++)
            if (old.keys[i] != UINT64_MAX)
                u64map_insert(map, old.keys[i], old.values[i]);
        free(old.keys);
        free(old.values);
    }
    u64map_insert(map, key, value);
}
