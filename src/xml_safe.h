/* xml_safe.h -- what the two XML readers share (internal): the safe
 * libxml2 parse, element lines, attribute values, stray text, value lists.
 *
 * The world XML reader (scene_read.c) and the URDF reader (urdf.c) parse
 * with the same safety measures (scene.h, "Safety"): no DTD, no entity
 * expansion, no network, no external entity ever loaded, any DOCTYPE
 * refused, nothing printed.  The parse returns a neutral result; each
 * reader words its own messages ("... not allowed in scene files"). */
#ifndef SS_XML_SAFE_H
#define SS_XML_SAFE_H

#include <libxml/tree.h>
#include <stddef.h>

/* Why a parse gave no document. */
typedef enum ssXmlFail {
  SS_XML_OK = 0,
  SS_XML_NOMEM,     /* the parser could not be started */
  SS_XML_DOCTYPE,   /* a DOCTYPE, a DTD or an entity reference to load */
  SS_XML_SYNTAX,    /* not well formed: message holds libxml2's words */
  SS_XML_NO_ROOT    /* well formed, but no root element */
} ssXmlFail;

typedef struct ssXmlResult {
  ssXmlFail fail;
  int line;            /* where it failed; 0 when not known */
  char message[1024];  /* SS_XML_SYNTAX: libxml2's message, no newline */
} ssXmlResult;

/* Parse buf[0, len) into a document the caller frees with xmlFreeDoc, or
 * return NULL and say why in *r.  huge != 0 lifts libxml2's size limits
 * (XML_PARSE_HUGE; the caller bounds len).  libxml2's global error
 * handlers and entity loader are replaced for the parse only.  Every
 * element's node->_private holds the line where its start tag begins, and
 * every text or CDATA node's that holds more than white space the line of
 * its first other character (ss_xml_line). */
xmlDocPtr ss_xml_parse(const char *buf, size_t len, int huge, ssXmlResult *r);

/* The line where an element's start tag begins, or where the text of a
 * text or CDATA node begins (its first character that is not white
 * space), as recorded by ss_xml_parse (libxml2's own node line is where
 * the start tag ends, the last line of a multi-line tag, and for text the
 * line of the next tag; it stops at 65535); other nodes: their libxml2
 * line, 0 when not known. */
int ss_xml_line(xmlNodePtr n);

/* The line of value k (0-based, as ss_xml_vec_next counts them) of
 * attribute `attr` of element el, found in the document's source buf[0,
 * len): an attribute may run over many lines (an exported height map's
 * arrays do), and libxml2 keeps no line for it.  The element is located as
 * the start tag whose turn in the source is its turn in document order;
 * whenever the source does not read as expected there (another encoding
 * than UTF-8 or ASCII, a reference such as &#32; inside the value), the
 * element's own line is returned. */
int ss_xml_value_line(const char *buf, size_t len, xmlNodePtr el,
                      const char *attr, long k);

/* The text of attribute a.  A single text child is returned as is
 * (*owned = NULL); otherwise the text is built and *owned is set to it,
 * for the caller to xmlFree.  Never NULL. */
const char *ss_xml_attr_text(xmlDocPtr doc, xmlAttrPtr a, xmlChar **owned);

/* n, a child of element <parent> that is not an element: 0 when it may
 * stand there (blank text, a comment, a processing instruction); otherwise
 * 1 with what is wrong in msg[cap] ("unexpected text 'x' inside <box> ..."). */
int ss_xml_stray(xmlNodePtr n, const char *parent, char *msg, size_t cap);

/* Next value of a vector attribute: values are separated by white space or
 * one comma.  Returns 1 with the value in [*tb, *te), 0 at the end, -1 on
 * an empty value (",," or a comma at either end). */
int ss_xml_vec_next(const char **pp, int first, const char **tb,
                    const char **te);
/* The number of values of a vector attribute; -1 on an empty value. */
long ss_xml_vec_count(const char *v);

/* Is name in the NULL-terminated list? */
int ss_xml_in_list(const char *name, const char *const *list);
/* names (NULL-terminated) as "a, b, c" in out[cap], cut short to fit. */
void ss_xml_join_names(char *out, size_t cap, const char *const *names);

#endif
