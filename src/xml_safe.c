/* xml_safe.c -- the safe libxml2 parse and the helpers the world XML and
 * URDF readers share (xml_safe.h). */
#include "xml_safe.h"

#include <libxml/parser.h>
#include <libxml/parserInternals.h>
#include <libxml/xmlerror.h>

#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* ---------------------------------------------------------------------- */
/* libxml2: safe parsing                                                   */

typedef struct xmlGuard {
  startElementNsSAX2Func start; /* libxml2's tree builder */
  charactersSAXFunc characters; /* its text and CDATA builders */
  cdataBlockSAXFunc cdata;
  int doctype_line;  /* > 0: a DOCTYPE was met (parsing stopped there) */
  int entity_refused;
  int have_error;
  int error_line;
  char error_msg[400];
} xmlGuard;

static xmlGuard *guard_of(void *ctx)
{
  xmlParserCtxtPtr p = (xmlParserCtxtPtr)ctx;
  return p ? (xmlGuard *)p->_private : NULL;
}

/* Structured error handler: keep the first error, print nothing. */
static void on_xml_error(void *data, xmlErrorPtr err)
{
  xmlGuard *g = (xmlGuard *)data;
  if (!g || !err || err->level < XML_ERR_ERROR || g->have_error) return;
  g->have_error = 1;
  g->error_line = err->line;
  snprintf(g->error_msg, sizeof g->error_msg, "%s",
           err->message ? err->message : "malformed XML");
  size_t n = strlen(g->error_msg);
  while (n > 0 && (g->error_msg[n - 1] == '\n' || g->error_msg[n - 1] == ' '))
    g->error_msg[--n] = 0;
}

static void on_generic_error(void *data, const char *msg, ...)
{
  (void)data;
  (void)msg;
}

/* Any DOCTYPE stops the parser before its internal subset is read. */
static void on_internal_subset(void *ctx, const xmlChar *name,
                               const xmlChar *external_id,
                               const xmlChar *system_id)
{
  (void)name;
  (void)external_id;
  (void)system_id;
  xmlParserCtxtPtr p = (xmlParserCtxtPtr)ctx;
  xmlGuard *g = guard_of(ctx);
  if (g && !g->doctype_line)
    g->doctype_line = p && p->input && p->input->line > 0 ? p->input->line : 1;
  xmlStopParser(p);
}

/* Build the element as usual, then record the line of its '<' in the
 * node's application pointer.  The parser is at the end of the start tag;
 * a start tag holds no other '<' (attribute values cannot), so the tag
 * begins at the last '<' before the current position. */
static void on_start_element(void *ctx, const xmlChar *localname,
                             const xmlChar *prefix, const xmlChar *uri,
                             int nb_namespaces, const xmlChar **namespaces,
                             int nb_attributes, int nb_defaulted,
                             const xmlChar **attributes)
{
  xmlParserCtxtPtr p = (xmlParserCtxtPtr)ctx;
  xmlGuard *g = guard_of(ctx);
  if (!g || !g->start) return;
  g->start(ctx, localname, prefix, uri, nb_namespaces, namespaces,
           nb_attributes, nb_defaulted, attributes);
  xmlNodePtr node = p->node;
  xmlParserInputPtr in = p->input;
  if (!node || !in || !in->cur || !in->base || in->line <= 0) return;
  const xmlChar *q = in->cur;
  int nl = 0;
  while (q > in->base && q[-1] != '<') {
    q--;
    if (*q == '\n') nl++;
  }
  int line = q > in->base && in->line - nl > 0 ? in->line - nl : in->line;
  node->_private = (void *)(intptr_t)line;
}

/* XML white space */
static int is_space(char ch)
{
  return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r';
}

/* After text ch[0, len) went into the text or CDATA node last in the
 * current element: record in the node's application pointer the line of
 * its first character that is not white space (the one a message about
 * stray text quotes).  libxml2's own line of a text node is where the
 * parser stood when it made the node, the end of the first piece of text
 * it delivered, which is the line of the next tag for ordinary text.  The
 * parser delivers a piece once it has read past it, so its last character
 * is on the current line and character k on that line less the newlines
 * in ch[k, len). */
static void record_text_line(xmlParserCtxtPtr p, const xmlChar *ch, int len)
{
  xmlNodePtr t = p && p->node ? p->node->last : NULL;
  if (!t || t->_private || !p->input || p->input->line <= 0 ||
      (t->type != XML_TEXT_NODE && t->type != XML_CDATA_SECTION_NODE))
    return;
  int k = 0;
  while (k < len && is_space((char)ch[k])) k++;
  if (k == len) return;
  int nl = 0;
  for (int i = k; i < len; i++)
    if (ch[i] == '\n') nl++;
  int line = p->input->line - nl;
  t->_private = (void *)(intptr_t)(line > 0 ? line : 1);
}

static void on_characters(void *ctx, const xmlChar *ch, int len)
{
  xmlGuard *g = guard_of(ctx);
  if (!g || !g->characters) return;
  g->characters(ctx, ch, len);
  record_text_line((xmlParserCtxtPtr)ctx, ch, len);
}

static void on_cdata(void *ctx, const xmlChar *ch, int len)
{
  xmlGuard *g = guard_of(ctx);
  if (!g || !g->cdata) return;
  g->cdata(ctx, ch, len);
  record_text_line((xmlParserCtxtPtr)ctx, ch, len);
}

/* Deny-by-default external entity loader: nothing is ever fetched. */
static xmlParserInputPtr deny_entity_loader(const char *url, const char *id,
                                            xmlParserCtxtPtr ctxt)
{
  (void)url;
  (void)id;
  xmlGuard *g = guard_of(ctxt);
  if (g) g->entity_refused = 1;
  return NULL;
}

/* What went wrong with a finished parse, into *r (SS_XML_OK: nothing). */
static void judge(xmlParserCtxtPtr p, xmlDocPtr doc, const xmlGuard *g,
                  ssXmlResult *r)
{
  if (g->doctype_line) {
    r->fail = SS_XML_DOCTYPE;
    r->line = g->doctype_line;
  } else if (!p->wellFormed || !doc) {
    r->fail = SS_XML_SYNTAX;
    if (g->have_error) {
      r->line = g->error_line;
      snprintf(r->message, sizeof r->message, "%s", g->error_msg);
    } else {
      xmlErrorPtr le = xmlCtxtGetLastError(p);
      r->line = le ? le->line : 0;
      snprintf(r->message, sizeof r->message, "%s",
               le && le->message ? le->message : "malformed document");
    }
    /* one line, as every other message (libxml2 ends its messages with a
     * newline and puts the bad bytes of an encoding error on a line of
     * their own) */
    size_t n = strlen(r->message);
    while (n > 0 && (r->message[n - 1] == '\n' || r->message[n - 1] == ' '))
      r->message[--n] = 0;
    for (char *q = r->message; *q; q++)
      if (*q == '\n') *q = ' ';
  } else if (doc->intSubset || doc->extSubset || g->entity_refused) {
    r->fail = SS_XML_DOCTYPE;
    r->line = 1;
  } else if (!xmlDocGetRootElement(doc)) {
    r->fail = SS_XML_NO_ROOT;
    r->line = 1;
  }
}

xmlDocPtr ss_xml_parse(const char *buf, size_t len, int huge, ssXmlResult *r)
{
  memset(r, 0, sizeof *r);
  xmlInitParser();
  xmlGuard g;
  memset(&g, 0, sizeof g);

  /* libxml2's handlers are global: install ours for this parse only */
  xmlStructuredErrorFunc old_serror = xmlStructuredError;
  void *old_sctx = xmlStructuredErrorContext;
  xmlGenericErrorFunc old_gerror = xmlGenericError;
  void *old_gctx = xmlGenericErrorContext;
  xmlExternalEntityLoader old_loader = xmlGetExternalEntityLoader();
  xmlSetStructuredErrorFunc(&g, on_xml_error);
  xmlSetGenericErrorFunc(NULL, on_generic_error);
  xmlSetExternalEntityLoader(deny_entity_loader);

  xmlDocPtr doc = NULL;
  xmlParserCtxtPtr p = xmlCreateMemoryParserCtxt(buf, (int)len);
  if (!p) {
    r->fail = SS_XML_NOMEM;
  } else {
    p->_private = &g;
    if (p->sax) {
      p->sax->internalSubset = on_internal_subset;
      g.start = p->sax->startElementNs;
      if (g.start) p->sax->startElementNs = on_start_element;
      /* white space goes to the same builder (libxml2 compares the two
       * pointers to tell whether blanks need telling apart: keep them
       * equal) */
      g.characters = p->sax->characters;
      if (g.characters && p->sax->ignorableWhitespace == g.characters)
        p->sax->ignorableWhitespace = on_characters;
      if (g.characters) p->sax->characters = on_characters;
      g.cdata = p->sax->cdataBlock;
      if (g.cdata) p->sax->cdataBlock = on_cdata;
    }
    /* never XML_PARSE_NOENT, XML_PARSE_DTDLOAD, XML_PARSE_DTDATTR or
     * XML_PARSE_XINCLUDE */
    xmlCtxtUseOptions(p, XML_PARSE_NONET | XML_PARSE_BIG_LINES |
                             (huge ? XML_PARSE_HUGE : 0));
    xmlParseDocument(p);
    doc = p->myDoc;
    p->myDoc = NULL;
    judge(p, doc, &g, r);
    if (r->fail != SS_XML_OK && doc) {
      xmlFreeDoc(doc);
      doc = NULL;
    }
    xmlFreeParserCtxt(p);
  }

  xmlSetExternalEntityLoader(old_loader);
  xmlSetGenericErrorFunc(old_gctx, old_gerror);
  xmlSetStructuredErrorFunc(old_sctx, old_serror);
  return doc;
}

int ss_xml_line(xmlNodePtr n)
{
  if ((n->type == XML_ELEMENT_NODE || n->type == XML_TEXT_NODE ||
       n->type == XML_CDATA_SECTION_NODE) && n->_private)
    return (int)(intptr_t)n->_private;
  long l = xmlGetLineNo(n);
  return l > 0 && l < INT_MAX ? (int)l : 0;
}

/* ---------------------------------------------------------------------- */
/* lines of values in the source                                           */

/* The number of elements before el in document order. */
static long element_ordinal(xmlNodePtr el)
{
  xmlNodePtr root = el;
  while (root->parent && root->parent->type == XML_ELEMENT_NODE)
    root = root->parent;
  long n = 0;
  for (xmlNodePtr x = root; x;) {
    if (x == el) return n;
    n++;
    /* the next element in document order: the first child element, else
     * the next sibling element of x or of its nearest ancestor that has
     * one, below the root */
    xmlNodePtr next = NULL;
    for (xmlNodePtr k = x->children; k && !next; k = k->next)
      if (k->type == XML_ELEMENT_NODE) next = k;
    for (xmlNodePtr up = x; !next && up && up != root; up = up->parent)
      for (xmlNodePtr k = up->next; k && !next; k = k->next)
        if (k->type == XML_ELEMENT_NODE) next = k;
    x = next;
  }
  return -1;
}

/* A source reader that counts lines as libxml2 does (LF, CR LF and a lone
 * CR each end one). */
typedef struct srcScan {
  const char *p, *end;
  int line;
} srcScan;

static void scan_step(srcScan *s)
{
  if (*s->p == '\n' || (*s->p == '\r' && (s->p + 1 >= s->end || s->p[1] != '\n')))
    s->line++;
  s->p++;
}

/* Skip to just after `mark`; 0 when it is not found. */
static int scan_past(srcScan *s, const char *mark)
{
  size_t n = strlen(mark);
  while (s->p < s->end) {
    if ((size_t)(s->end - s->p) >= n && !memcmp(s->p, mark, n)) {
      for (size_t i = 0; i < n; i++) scan_step(s);
      return 1;
    }
    scan_step(s);
  }
  return 0;
}

static int name_char(char ch)
{
  return ch && !is_space(ch) && ch != '=' && ch != '>' && ch != '/' &&
         ch != '<' && ch != '"' && ch != '\'';
}

int ss_xml_value_line(const char *buf, size_t len, xmlNodePtr el,
                      const char *attr, long k)
{
  int fallback = ss_xml_line(el);
  long want = buf && attr ? element_ordinal(el) : -1;
  if (want < 0) return fallback;
  srcScan s = {buf, buf + len, 1};
  long seen = -1;
  /* the start tags in order, past the prolog, comments, PIs and CDATA */
  while (s.p < s.end) {
    if (*s.p != '<') {
      scan_step(&s);
      continue;
    }
    const char *q = s.p + 1;
    size_t left = (size_t)(s.end - q);
    int ok = 1;
    if (left >= 3 && !memcmp(q, "!--", 3)) ok = scan_past(&s, "-->");
    else if (left >= 8 && !memcmp(q, "![CDATA[", 8)) ok = scan_past(&s, "]]>");
    else if (left >= 1 && *q == '?') ok = scan_past(&s, "?>");
    else if (left >= 1 && *q == '!') ok = scan_past(&s, ">");
    else if (left >= 1 && *q == '/') ok = scan_past(&s, ">");
    else if (++seen == want) break;
    else scan_step(&s);
    if (!ok) return fallback;
  }
  if (seen != want || s.p >= s.end || s.line != fallback) return fallback;
  /* the tag's name, then its attributes */
  scan_step(&s);
  const char *nm = (const char *)el->name;
  size_t nl = strlen(nm);
  if ((size_t)(s.end - s.p) <= nl || memcmp(s.p, nm, nl) || name_char(s.p[nl]))
    return fallback;
  for (size_t i = 0; i < nl; i++) scan_step(&s);
  size_t al = strlen(attr);
  for (;;) {
    while (s.p < s.end && is_space(*s.p)) scan_step(&s);
    if (s.p >= s.end || !name_char(*s.p)) return fallback;
    const char *an = s.p;
    while (s.p < s.end && name_char(*s.p)) scan_step(&s);
    int match = (size_t)(s.p - an) == al && !memcmp(an, attr, al);
    while (s.p < s.end && is_space(*s.p)) scan_step(&s);
    if (s.p >= s.end || *s.p != '=') return fallback;
    scan_step(&s);
    while (s.p < s.end && is_space(*s.p)) scan_step(&s);
    if (s.p >= s.end || (*s.p != '"' && *s.p != '\'')) return fallback;
    char quote = *s.p;
    scan_step(&s);
    const char *v = s.p, *ve = memchr(v, quote, (size_t)(s.end - v));
    if (!ve) return fallback;
    if (!match) {
      while (s.p < ve) scan_step(&s);
      scan_step(&s);
      continue;
    }
    if (memchr(v, '&', (size_t)(ve - v))) return fallback;
    /* value k: tokens as ss_xml_vec_next splits them */
    long idx = -1;
    int in_token = 0;
    while (s.p < ve) {
      char ch = *s.p;
      if (is_space(ch) || ch == ',') {
        in_token = 0;
      } else if (!in_token) {
        in_token = 1;
        if (++idx == k) return s.line;
      }
      scan_step(&s);
    }
    return fallback;
  }
}

/* ---------------------------------------------------------------------- */
/* attributes, children, value lists                                      */

static int is_blank(const xmlChar *s)
{
  if (!s) return 1;
  for (; *s; s++)
    if (!is_space((char)*s)) return 0;
  return 1;
}

const char *ss_xml_attr_text(xmlDocPtr doc, xmlAttrPtr a, xmlChar **owned)
{
  *owned = NULL;
  if (a->children && a->children->type == XML_TEXT_NODE &&
      !a->children->next && a->children->content)
    return (const char *)a->children->content;
  xmlChar *v = xmlNodeListGetString(doc, a->children, 1);
  *owned = v;
  return v ? (const char *)v : "";
}

int ss_xml_stray(xmlNodePtr n, const char *parent, char *msg, size_t cap)
{
  switch (n->type) {
  case XML_TEXT_NODE:
  case XML_CDATA_SECTION_NODE:
    if (is_blank(n->content)) return 0;
    {
      const char *t = (const char *)n->content;
      while (is_space(*t)) t++;
      int len = 0;
      while (t[len] && !is_space(t[len]) && len < 30) len++;
      snprintf(msg, cap, "unexpected text '%.*s' inside <%s> (values go in "
               "attributes)", len, t, parent);
      return 1;
    }
  case XML_COMMENT_NODE:
  case XML_PI_NODE:
    return 0;
  default:
    snprintf(msg, cap, "unexpected content inside <%s>", parent);
    return 1;
  }
}

int ss_xml_vec_next(const char **pp, int first, const char **tb,
                    const char **te)
{
  const char *p = *pp;
  while (is_space(*p)) p++;
  if (*p == ',') {
    if (first) return -1;
    p++;
    while (is_space(*p)) p++;
    if (*p == 0 || *p == ',') return -1;
  }
  if (*p == 0) {
    *pp = p;
    return 0;
  }
  *tb = p;
  while (*p && !is_space(*p) && *p != ',') p++;
  *te = p;
  *pp = p;
  return 1;
}

long ss_xml_vec_count(const char *v)
{
  const char *p = v, *tb, *te;
  long n = 0;
  int r;
  while ((r = ss_xml_vec_next(&p, n == 0, &tb, &te)) == 1) n++;
  return r < 0 ? -1 : n;
}

int ss_xml_in_list(const char *name, const char *const *list)
{
  for (int i = 0; list[i]; i++)
    if (!strcmp(list[i], name)) return 1;
  return 0;
}

void ss_xml_join_names(char *out, size_t cap, const char *const *names)
{
  size_t k = 0;
  out[0] = 0;
  for (int i = 0; names[i]; i++) {
    int n = snprintf(out + k, cap - k, "%s%s", i ? ", " : "", names[i]);
    if (n < 0 || (size_t)n >= cap - k) break;
    k += (size_t)n;
  }
}
