/* dynamics.c - parsing the dynamics statements: masses, gravity and the applied force elements (no rows).
 *
 * A force element's keyword, attachments and keys come from its row in
 * forces.def; the forms that differ (a point force's vector, a torque's
 * angle(e), a gforce's coordinate) are read by kind.
 */
#include "parser.h"

#include <stdio.h>
#include <string.h>

#define KEYBIT(k) (1u << (k))

/* The keys of a mass (a force's are its row's in forces.def). */
static const unsigned mass_keys = KEYBIT(DKEY_M) | KEYBIT(DKEY_J) | KEYBIT(DKEY_ANGLE);

/* A spatial body's own mass: J is the tensor's diagonal, the products
   its off-diagonal entries; a spatial mass element has no angle, no J. */
static const unsigned spatial_body_mass = KEYBIT(DKEY_M) | KEYBIT(DKEY_J) | KEYBIT(DKEY_JXY)
                                          | KEYBIT(DKEY_JXZ) | KEYBIT(DKEY_JYZ);

/* The keys in `allowed`, listed as "m, J or com" for messages. */
static void list_keys(char *buf, size_t size, unsigned allowed, const char *extra)
{
    const char *words[DKEY_COUNT + 1];
    int n = 0;
    for (int k = 0; k < DKEY_COUNT; k++)
        if (allowed & KEYBIT(k))
            words[n++] = dyn_key_names[k];
    if (extra)
        words[n++] = extra;
    size_t len = 0;
    buf[0] = '\0';
    for (int i = 0; i < n && len < size; i++)
        len += (size_t)snprintf(buf + len, size - len, "%s%s", i == 0 ? "" : i == n - 1 ? " or " : ", ",
                                words[i]);
}

/* at(x, y), spatial at(x, y, z): a point given by expressions of the
   coordinates, into a. */
static void at_point(Parser *p, AstAttach *a)
{
    a->at = true;
    a->name = NULL;
    a->pos = p->tok.pos;
    parse_advance(p);
    parse_offset(p, p->spatial ? "at(x, y, z)" : "at(x, y)", a);
}

/* A vector of the file's dimension: (x, y), spatial (x, y, z); what
   names it in messages (its spatial form when the file is spatial). */
static void vector(Parser *p, const char *what, const char *spatial_what, Ast **out)
{
    if (p->spatial)
        parse_components(p, spatial_what, 3, out);
    else
        parse_pair(p, what, &out[0], &out[1]);
}

/* dyn_attachment = 'at' pair | NAME [pair]   (frame_only: a body or ground alone) */
static void dyn_attachment(Parser *p, Stmt *s, int slot, int count, bool frame_only)
{
    AstAttach *a = &s->attach[slot];
    const char *kw = dyn_keyword(s);
    const char *nth = count == 1 ? "" : slot == 0 ? "first " : "second ";
    if (p->tok.kind != TOK_IDENT || (parse_is_reserved(&p->tok) && !lex_is_word(&p->tok, "ground")))
        parse_expected(p, "%s as the %sattachment of %s '%s'",
                 frame_only ? "a body or ground" : "a body, point, ground or at(x, y)", nth, kw,
                 s->name);
    Token name = p->tok;
    Lexer saved = p->lx;
    parse_advance(p);
    if (frame_only && lex_is_word(&name, "at") && p->tok.kind == TOK_LPAREN)
        diag_fail(p->diag, name.pos, "%s '%s' acts on bodies' angles: at(x, y) is a point; "
                  "name a body or ground", kw, s->name);
    if (!frame_only && lex_is_word(&name, "at") && p->tok.kind == TOK_LPAREN) {
        p->lx = saved;      /* back to 'at' for at_point */
        p->tok = name;
        at_point(p, a);
        return;
    }
    a->name = parse_token_text(p, &name);
    a->pos = name.pos;
    if (p->tok.kind != TOK_LPAREN)
        return;
    if (frame_only)
        diag_fail(p->diag, p->tok.pos, "%s '%s' acts on bodies' angles: write '%s' alone, "
                  "without an offset", kw, s->name, a->name);
    char what[DIAG_MESSAGE_MAX];
    snprintf(what, sizeof what, "the offset of '%s'", a->name);
    a->has_offset = true;
    parse_offset(p, what, a);
}

/* keys = {KEY '=' expr | 'com' pair | 'at' pair}, each at most once;
   com and at only where the form takes them (a body's own mass, with
   com, turns with the body: no angle key). */
static void dyn_keys(Parser *p, Stmt *s, bool com, bool at)
{
    bool mass = s->kind == STMT_MASS;
    unsigned allowed = (mass ? mass_keys : force_info[s->force].keys) & (com ? ~KEYBIT(DKEY_ANGLE) : ~0u);
    if (p->spatial && mass)
        allowed = com ? spatial_body_mass : KEYBIT(DKEY_M);
    while (p->tok.kind == TOK_IDENT) {
        bool is_com = com && lex_is_word(&p->tok, "com"), is_at = at && lex_is_word(&p->tok, "at");
        if ((is_com && s->vec[0]) || (is_at && s->attach[0].at))
            diag_fail(p->diag, p->tok.pos, "'%.*s' given twice for %s '%s'", p->tok.len,
                      p->tok.start, dyn_keyword(s), s->name);
        if (is_com) {
            s->vec_pos = p->tok.pos;
            parse_advance(p);
            vector(p, "com(sx, sy)", "com(sx, sy, sz)", s->vec);
            continue;
        }
        if (is_at) {
            at_point(p, &s->attach[0]);
            continue;
        }
        int k = 0;
        while (k < DKEY_COUNT && !lex_is_word(&p->tok, dyn_key_names[k]))
            k++;
        char list[128];
        list_keys(list, sizeof list, allowed, com ? (p->spatial ? "com(sx, sy, sz)" : "com(sx, sy)")
                  : at ? (p->spatial ? "at(x, y, z)" : "at(x, y)") : NULL);
        if (k == DKEY_COUNT || !(allowed & KEYBIT(k)))
            diag_fail(p->diag, p->tok.pos, "unknown key '%.*s' for %s '%s': expected %s",
                      p->tok.len, p->tok.start, dyn_keyword(s), s->name, list);
        if (s->key[k])
            diag_fail(p->diag, p->tok.pos, "'%s' given twice for %s '%s'", dyn_key_names[k],
                      dyn_keyword(s), s->name);
        s->key_pos[k] = p->tok.pos;
        parse_advance(p);
        if (p->tok.kind != TOK_EQ)
            parse_expected(p, "'=' after '%s'", dyn_key_names[k]);
        parse_advance(p);
        if (p->spatial && k == DKEY_J) {    /* the tensor's diagonal; key[J] marks it given */
            parse_components(p, "J = (Jxx, Jyy, Jzz)", 3, s->inertia);
            s->key[k] = s->inertia[0];
            continue;
        }
        s->key[k] = parse_expr(p);
    }
}

/* mass = 'mass' NAME keys          (a body's or point's own mass; com for a body)
        | 'mass' NAME ':' keys      (a mass element: at(x, y) required) */
void parse_mass(Parser *p, Stmt *s)
{
    s->kind = STMT_MASS;
    parse_advance(p);
    s->name = parse_declared_name(p, "mass", &s->name_pos);
    if (p->tok.kind == TOK_COLON) {
        s->declares = true;
        parse_advance(p);
        dyn_keys(p, s, false, true);
        if (!s->attach[0].at)
            parse_expected(p, "'%s' for the mass element '%s' (or 'mass BODY m = ...' "
                     "without ':' for a body's own mass)", p->spatial ? "at(x, y, z)" : "at(x, y)",
                     s->name);
    } else {
        dyn_keys(p, s, true, false);
    }
    if (!s->key[DKEY_M])
        parse_expected(p, "'m = ...' for mass '%s'", s->name);
}

/* torque = 'torque' NAME ':' (BODY | 'angle' '(' expr ')') '=' expr */
static void dyn_torque(Parser *p, Stmt *s)
{
    Lexer saved = p->lx;
    Token word = p->tok;
    if (lex_is_word(&word, "angle")) {
        parse_advance(p);
        if (p->tok.kind == TOK_LPAREN) {
            s->eq_pos = word.pos;
            parse_advance(p);
            s->lhs = parse_expr(p);
            if (p->tok.kind != TOK_RPAREN)
                parse_expected(p, "')' after the angle of torque '%s'", s->name);
            parse_advance(p);
        } else {
            p->lx = saved;  /* a body called angle */
            p->tok = word;
        }
    }
    if (!s->lhs)
        dyn_attachment(p, s, 0, 1, true);
    if (p->tok.kind != TOK_EQ)
        parse_expected(p, "'=' and the torque of '%s'", s->name);
    parse_advance(p);
    if (p->spatial && !s->lhs) {    /* a spatial body's torque: global components */
        s->force = FORCE_BODY_TORQUE;
        s->vec_pos = p->tok.pos;
        parse_components(p, "the torque (tx, ty, tz)", 3, s->vec);
        return;
    }
    s->value = parse_expr(p);
}

/* spatial rspring = 'rspring' NAME ':' JOINT keys   (about a revolute's or
   cylindrical's axis: its angle(JOINT)) */
static void dyn_spatial_rspring(Parser *p, Stmt *s)
{
    AstAttach *a = &s->attach[0];
    if (p->tok.kind != TOK_IDENT || parse_is_reserved(&p->tok))
        parse_expected(p, "a revolute or cylindrical joint after 'rspring %s:' (a spatial rspring "
                 "acts about the joint's axis)", s->name);
    a->name = parse_token_text(p, &p->tok);
    a->pos = p->tok.pos;
    parse_advance(p);
    dyn_keys(p, s, false, false);
}

/* gravity = 'gravity' pair */
void parse_gravity(Parser *p, Stmt *s)
{
    s->kind = STMT_GRAVITY;
    parse_advance(p);
    s->vec_pos = p->tok.pos;
    vector(p, "gravity (gx, gy)", "gravity (gx, gy, gz)", s->vec);
}

/* force = 'force' NAME ':' attachment pair */
static void point_force(Parser *p, Stmt *s)
{
    AstAttach *a = &s->attach[0];
    SrcPos offset_pos = p->tok.pos;
    dyn_attachment(p, s, 0, 1, false);
    if (p->tok.kind != TOK_LPAREN && a->has_offset && !a->at) {
        /* `force F: body (fx, fy)`: the pair was the force, not an offset */
        a->has_offset = false;
        s->vec[0] = a->sx, s->vec[1] = a->sy, s->vec[2] = a->sz;
        a->sx = a->sy = a->sz = NULL;
        s->vec_pos = offset_pos;
        return;
    }
    s->vec_pos = p->tok.pos;
    vector(p, "the force (fx, fy)", "the force (fx, fy, fz)", s->vec);
}

/* force element = KIND NAME ':' operands, by kind (forces.def):
     'force' NAME ':' attachment pair
   | 'torque' NAME ':' (BODY | 'angle' '(' expr ')') '=' expr
   | ('spring' | 'rspring') NAME ':' attachment attachment keys
   | 'gforce' NAME ':' COORDINATE '=' expr */
void parse_force(Parser *p, Stmt *s, ForceKind kind)
{
    const ForceInfo *info = &force_info[kind];
    s->kind = STMT_FORCE;
    s->force = kind;
    parse_advance(p);
    s->name = parse_declared_name(p, info->keyword, &s->name_pos);
    s->declares = true;
    if (p->tok.kind != TOK_COLON)
        parse_expected(p, "':' after the %s name '%s'", info->keyword, s->name);
    parse_advance(p);
    switch (kind) {
    case FORCE_POINT:
        point_force(p, s);
        return;
    case FORCE_TORQUE: case FORCE_BODY_TORQUE:
        dyn_torque(p, s);
        return;
    case FORCE_SPRING: case FORCE_RSPRING:
        if (p->spatial && kind == FORCE_RSPRING) {
            dyn_spatial_rspring(p, s);
            return;
        }
        for (int i = 0; i < info->attachments; i++)
            dyn_attachment(p, s, i, info->attachments, info->frame);
        dyn_keys(p, s, false, false);
        return;
    case FORCE_GENERAL:
        s->lhs = parse_expr(p);
        if (p->tok.kind != TOK_EQ)
            parse_expected(p, "'=' after the coordinate of gforce '%s'", s->name);
        s->eq_pos = p->tok.pos;
        parse_advance(p);
        s->value = parse_expr(p);
        return;
    case FORCE_KIND_COUNT:
        break;
    }
}
