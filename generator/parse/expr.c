/* expr.c - the expression grammar of .mech files: precedence climbing over a priority table.
 *
 * In the manner of Lua's lparser.c subexpr: each binary operator has a left
 * and a right priority, and an operator is taken while its left priority
 * exceeds the caller's limit. Nesting (parentheses, calls, unary operators
 * and the right operand of '^', the only unbounded recursions) is counted
 * against limits->max_depth, so hostile input ends in an error, never a
 * stack overflow.
 */
#include "parser.h"

#define PARSE_PI 3.14159265358979323846

static int column_of(const Parser *p, SrcPos pos)
{
    int line, col;
    diag_locate(p->diag, pos.offset, &line, &col);
    return col;
}

static Ast *new_ast(Parser *p, AstKind kind, SrcPos pos)
{
    Ast *ast = arena_alloc(p->arena, sizeof *ast);
    ast->kind = kind;
    ast->pos = pos;
    return ast;
}

void parse_enter_level(Parser *p, SrcPos pos)
{
    if (++p->depth > p->limits->max_depth)
        diag_fail(p->diag, pos, "expression nested deeper than the limit of %d levels",
                  p->limits->max_depth);
}

void parse_leave_level(Parser *p) { p->depth--; }

static Ast *subexpr(Parser *p, int limit);

/* expr = subexpr(0) */
Ast *parse_expr(Parser *p) { return subexpr(p, 0); }

/* Binary operators: left and right priority (Lua lparser.c priority[]).
   '^' has right < left, so a chain nests to the right; its left priority is
   above UNARY_PRIORITY, so -x^2 is -(x^2), while -a*b is (-a)*b. */
typedef struct BinaryPriority {
    TokKind tok;
    DagOp op;
    int left, right;
} BinaryPriority;

static const BinaryPriority binary_priority[] = {
    {TOK_PLUS, OP_ADD, 10, 10},
    {TOK_MINUS, OP_SUB, 10, 10},
    {TOK_STAR, OP_MUL, 11, 11},
    {TOK_SLASH, OP_DIV, 11, 11},
    {TOK_CARET, OP_POW, 14, 13},
};

enum { UNARY_PRIORITY = 12 };

static const BinaryPriority *binary_op(TokKind kind)
{
    for (size_t i = 0; i < sizeof binary_priority / sizeof binary_priority[0]; i++)
        if (binary_priority[i].tok == kind)
            return &binary_priority[i];
    return NULL;
}

/* coordinate = NAME ['.' NAME]   (the operand of der) */
static Ast *coordinate(Parser *p)
{
    if (p->tok.kind != TOK_IDENT || parse_is_reserved(&p->tok))
        parse_expected(p, "a coordinate name in der()");
    Token name = p->tok;
    parse_advance(p);
    if (p->tok.kind != TOK_DOT) {
        Ast *ast = new_ast(p, AST_NAME, name.pos);
        ast->name = parse_token_text(p, &name);
        return ast;
    }
    parse_advance(p);
    if (p->tok.kind != TOK_IDENT)
        parse_expected(p, "a coordinate name after '%.*s.'", name.len, name.start);
    Ast *ast = new_ast(p, AST_MEMBER, name.pos);
    ast->name = parse_token_text(p, &name);
    ast->member = parse_token_text(p, &p->tok);
    ast->member_pos = p->tok.pos;
    parse_advance(p);
    return ast;
}


/* slide = 'slide' '(' NAME ')'   (NAME: a prismatic or pointline joint,
   resolved by the model; slide is no reserved word, only this form is);
   angle = 'angle' '(' NAME ')' in a spatial file is read the same way */
static Ast *slide(Parser *p, const Token *word)
{
    Ast *ast = new_ast(p, AST_SLIDE, word->pos);
    parse_advance(p);
    if (p->tok.kind != TOK_IDENT)
        parse_expected(p, "a joint name in %.*s(...)", word->len, word->start);
    ast->name = parse_token_text(p, &p->tok);
    ast->member_pos = p->tok.pos;
    parse_advance(p);
    if (p->tok.kind != TOK_RPAREN)
        parse_expected(p, "')' after the joint name in %.*s(%s", word->len, word->start, ast->name);
    parse_advance(p);
    return ast;
}

/* der = 'der' '(' coordinate ')' */
static Ast *derivative(Parser *p)
{
    Ast *ast = new_ast(p, AST_DER, p->tok.pos);
    parse_advance(p);
    if (p->tok.kind != TOK_LPAREN)
        parse_expected(p, "'(' after 'der'");
    parse_enter_level(p, p->tok.pos);
    parse_advance(p);
    ast->lhs = coordinate(p);
    if (p->tok.kind != TOK_RPAREN)
        parse_expected(p, "')' after the coordinate in der()");
    parse_advance(p);
    parse_leave_level(p);
    return ast;
}

/* call = FUNCTION '(' [expr {',' expr}] ')'   with exactly the function's arity */
static Ast *call(Parser *p, DagOp op)
{
    const DagOpInfo *info = &dag_op_info[op];
    Ast *ast = new_ast(p, AST_CALL, p->tok.pos);
    ast->op = op;
    parse_advance(p);
    if (p->tok.kind != TOK_LPAREN)
        parse_expected(p, "'(' after the function name '%s'", info->spelling);
    SrcPos open = p->tok.pos;
    parse_enter_level(p, open);
    parse_advance(p);
    int n = 0;
    SrcPos excess = {0};
    if (p->tok.kind != TOK_RPAREN) {
        for (;;) {
            SrcPos arg_pos = p->tok.pos;
            Ast *arg = parse_expr(p);
            if (n == 0)
                ast->lhs = arg;
            else if (n == 1)
                ast->rhs = arg;
            if (n == info->arity)
                excess = arg_pos;
            n++;
            if (p->tok.kind != TOK_COMMA)
                break;
            parse_advance(p);
        }
    }
    if (p->tok.kind != TOK_RPAREN)
        parse_expected(p, "')' to close '%s(' at column %d", info->spelling, column_of(p, open));
    SrcPos close = p->tok.pos;
    if (n != info->arity)
        diag_fail(p->diag, n > info->arity ? excess : close,
                  "%s() takes %d argument%s, found %d", info->spelling, info->arity,
                  info->arity == 1 ? "" : "s", n);
    parse_advance(p);
    parse_leave_level(p);
    return ast;
}

/* primary = NUMBER | 'pi' | 't' | NAME ['.' NAME] | call | der | '(' expr ')' */
static Ast *primary(Parser *p)
{
    Token tok = p->tok;
    if (tok.kind == TOK_NUMBER) {
        Ast *ast = new_ast(p, AST_NUM, tok.pos);
        ast->num = tok.num;
        parse_advance(p);
        return ast;
    }
    if (tok.kind == TOK_LPAREN) {
        parse_enter_level(p, tok.pos);
        parse_advance(p);
        Ast *ast = parse_expr(p);
        if (p->tok.kind != TOK_RPAREN)
            parse_expected(p, "')' to close the '(' at column %d", column_of(p, tok.pos));
        parse_advance(p);
        parse_leave_level(p);
        return ast;
    }
    if (tok.kind != TOK_IDENT)
        parse_expected(p, "an expression");
    int op = dag_function_from_name(tok.start, tok.len);
    if (op >= 0 && dag_op_is_function((DagOp)op))
        return call(p, (DagOp)op);
    if (lex_is_word(&tok, "der"))
        return derivative(p);
    parse_advance(p);
    if (p->tok.kind == TOK_LPAREN && lex_is_word(&tok, "slide"))
        return slide(p, &tok);
    if (p->tok.kind == TOK_LPAREN && p->spatial && lex_is_word(&tok, "angle")) {
        Ast *ast = slide(p, &tok);
        ast->kind = AST_ANGLE;
        return ast;
    }
    if (p->tok.kind == TOK_LPAREN)
        diag_fail(p->diag, tok.pos, "'%.*s' is not a function", tok.len, tok.start);
    Ast *ast;
    if (lex_is_word(&tok, "pi")) {
        ast = new_ast(p, AST_NUM, tok.pos);
        ast->num = PARSE_PI;
    } else if (lex_is_word(&tok, "t")) {
        ast = new_ast(p, AST_TIME, tok.pos);
    } else if (p->tok.kind == TOK_DOT) {
        parse_advance(p);
        if (p->tok.kind != TOK_IDENT)
            parse_expected(p, "a member name after '%.*s.'", tok.len, tok.start);
        ast = new_ast(p, AST_MEMBER, tok.pos);
        ast->name = parse_token_text(p, &tok);
        ast->member = parse_token_text(p, &p->tok);
        ast->member_pos = p->tok.pos;
        parse_advance(p);
    } else {
        ast = new_ast(p, AST_NAME, tok.pos);
        ast->name = parse_token_text(p, &tok);
    }
    return ast;
}

/* subexpr = ('-' | '+') subexpr(UNARY_PRIORITY) {binop subexpr(right)}
           | primary {binop subexpr(right)}
   taking each binop only while its left priority exceeds limit. An
   expression ends at the first token that cannot continue it, so
   "x = r/2 y = 0" splits after the 2. */
static Ast *subexpr(Parser *p, int limit)
{
    Ast *ast;
    if (p->tok.kind == TOK_MINUS || p->tok.kind == TOK_PLUS) {
        Token sign = p->tok;
        parse_enter_level(p, sign.pos);
        parse_advance(p);
        Ast *operand = subexpr(p, UNARY_PRIORITY);
        parse_leave_level(p);
        if (sign.kind == TOK_PLUS) {
            ast = operand;      /* unary plus is dropped */
        } else {
            ast = new_ast(p, AST_NEG, sign.pos);
            ast->lhs = operand;
        }
    } else {
        ast = primary(p);
    }
    for (;;) {
        const BinaryPriority *bin = binary_op(p->tok.kind);
        if (!bin || bin->left <= limit)
            return ast;
        Ast *node = new_ast(p, AST_BINARY, p->tok.pos);
        node->op = bin->op;
        node->lhs = ast;
        bool nests = bin->right < bin->left;    /* '^' chains recurse */
        if (nests)
            parse_enter_level(p, p->tok.pos);
        parse_advance(p);
        node->rhs = subexpr(p, bin->right);
        if (nests)
            parse_leave_level(p);
        ast = node;
    }
}
