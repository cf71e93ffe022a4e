/* SPDX-License-Identifier: MIT */
/* URDF -> mca_chain_t (start-up only). C++17 behind the extern "C" mca_chain_load_urdf().
 * TinyXML (urdfdom's own XML parser) is used first for a pre-scan that can name the line of a
 * faulty element; urdfdom then builds the model, whose console_bridge errors are captured into
 * the caller's message instead of being printed. */
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <exception>
#include <map>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_model/model.h>
#include <urdf_parser/urdf_parser.h>

#include "mca/chain.h"
#include "mca/err.h"

namespace {

/* Collects urdfdom's console messages while it parses (single-threaded start-up). */
class CaptureHandler : public console_bridge::OutputHandler {
  public:
    std::string text;
    void log(const std::string &msg, console_bridge::LogLevel level, const char *, int) override {
        if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
            if (!text.empty()) {
                text += "; ";
            }
            text += msg;
        }
    }
};

class CaptureScope {
  public:
    explicit CaptureScope(CaptureHandler *h) {
        console_bridge::useOutputHandler(h);
    }
    ~CaptureScope() {
        console_bridge::restorePreviousOutputHandler();
    }
    CaptureScope(const CaptureScope &) = delete;
    CaptureScope &operator=(const CaptureScope &) = delete;
};

struct Ctx {
    const char *path;
    char *err;
    size_t errlen;
    std::map<std::string, int> joint_line; /* joint name -> line in the file (0: unknown) */

    int fail(int rc, const char *fmt, ...) __attribute__((format(printf, 3, 4))) {
        if (err && errlen > 0) {
            int n = snprintf(err, errlen, "%s: ", path);
            if (n < 0) {
                n = 0;
            }
            if (static_cast<size_t>(n) < errlen) {
                va_list ap;
                va_start(ap, fmt);
                vsnprintf(err + n, errlen - static_cast<size_t>(n), fmt, ap);
                va_end(ap);
            }
        }
        return rc;
    }
    /* "LINE: joint 'name'" prefix text for a joint, without the line when it is unknown. */
    std::string joint_ref(const std::string &name) const {
        auto it = joint_line.find(name);
        std::string s;
        if (it != joint_line.end() && it->second > 0) {
            s = "line " + std::to_string(it->second) + ": ";
        }
        return s + "joint '" + name + "'";
    }
};

void pose_from_urdf(mca_pose_t *out, const urdf::Pose &p) {
    double x = p.rotation.x, y = p.rotation.y, z = p.rotation.z, w = p.rotation.w;
    const double n = std::sqrt(x * x + y * y + z * z + w * w);
    if (n > 0.0) {
        x /= n;
        y /= n;
        z /= n;
        w /= n;
    } else {
        w = 1.0;
    }
    out->R[0][0] = 1 - 2 * (y * y + z * z);
    out->R[0][1] = 2 * (x * y - z * w);
    out->R[0][2] = 2 * (x * z + y * w);
    out->R[1][0] = 2 * (x * y + z * w);
    out->R[1][1] = 1 - 2 * (x * x + z * z);
    out->R[1][2] = 2 * (y * z - x * w);
    out->R[2][0] = 2 * (x * z - y * w);
    out->R[2][1] = 2 * (y * z + x * w);
    out->R[2][2] = 1 - 2 * (x * x + y * y);
    out->p[0] = p.position.x;
    out->p[1] = p.position.y;
    out->p[2] = p.position.z;
}

/* Largest capsule radius among the <collision> cylinders/spheres of a link (0: none). */
double link_radius(const urdf::LinkConstSharedPtr &link) {
    std::vector<urdf::CollisionSharedPtr> cols = link->collision_array;
    if (cols.empty() && link->collision) {
        cols.push_back(link->collision);
    }
    double r = 0.0;
    for (const auto &c : cols) {
        if (!c || !c->geometry) {
            continue;
        }
        if (c->geometry->type == urdf::Geometry::CYLINDER) {
            r = std::fmax(r, std::static_pointer_cast<urdf::Cylinder>(c->geometry)->radius);
        } else if (c->geometry->type == urdf::Geometry::SPHERE) {
            r = std::fmax(r, std::static_pointer_cast<urdf::Sphere>(c->geometry)->radius);
        }
    }
    return r;
}

const char *type_name(int type) {
    switch (type) {
    case urdf::Joint::REVOLUTE:
        return "revolute";
    case urdf::Joint::CONTINUOUS:
        return "continuous";
    case urdf::Joint::PRISMATIC:
        return "prismatic";
    case urdf::Joint::FLOATING:
        return "floating";
    case urdf::Joint::PLANAR:
        return "planar";
    case urdf::Joint::FIXED:
        return "fixed";
    default:
        return "unknown";
    }
}

/* The text must be UTF-8 without NUL bytes before TinyXML (the pre-scan's and urdfdom's parser) reads it:
 * TinyXML steps over a UTF-8 lead byte by the length the byte announces, so a lead byte in the last three
 * bytes (0xF4 at the end of a name) carried its read past the string's end (heap overflow in
 * TiXmlBase::ReadName, found by fuzz/fuzz_urdf); a NUL ends its text early, silently. Strict UTF-8
 * (RFC 3629: no overlong forms, no surrogates, nothing above U+10FFFF), as XML's default encoding. */
int utf8_check(Ctx &cx, const std::string &text) {
    const unsigned char *s = reinterpret_cast<const unsigned char *>(text.data());
    const size_t n = text.size();
    int line = 1;
    size_t line_start = 0;
    for (size_t i = 0; i < n;) {
        const unsigned c = s[i];
        size_t len = 0;
        unsigned lo = 0x80, hi = 0xBF; /* the allowed range of the first continuation byte */
        if (c == 0) {
            return cx.fail(MCA_EPARSE, "line %d, column %zu: NUL byte: not a text file", line,
                           i - line_start + 1);
        } else if (c < 0x80) {
            if (c == '\n') {
                line++;
                line_start = i + 1;
            }
            i++;
            continue;
        } else if (c >= 0xC2 && c <= 0xDF) {
            len = 2;
        } else if (c >= 0xE0 && c <= 0xEF) {
            len = 3;
            lo = c == 0xE0 ? 0xA0 : 0x80;
            hi = c == 0xED ? 0x9F : 0xBF;
        } else if (c >= 0xF0 && c <= 0xF4) {
            len = 4;
            lo = c == 0xF0 ? 0x90 : 0x80;
            hi = c == 0xF4 ? 0x8F : 0xBF;
        }
        bool ok = len > 0 && i + len <= n;
        for (size_t k = 1; ok && k < len; k++) {
            ok = k == 1 ? s[i + k] >= lo && s[i + k] <= hi : (s[i + k] & 0xC0) == 0x80;
        }
        if (!ok) {
            return cx.fail(MCA_EPARSE,
                           "line %d, column %zu: byte 0x%02X is not UTF-8 text (a URDF is UTF-8 XML)", line,
                           i - line_start + 1, c);
        }
        i += len;
    }
    return MCA_OK;
}

/* Element nesting deeper than this is refused before any XML parser sees the text: TinyXML (the pre-scan's
 * and urdfdom's parser) descends recursively, one stack frame chain per element level, so a file nested
 * 50 000 deep overflows the stack. A robot's URDF nests about 5 deep (robot/link/collision/geometry/...). */
constexpr int kMaxDepth = 256;

/* Cheap scan of the element structure: start tags deepen, end tags return, empty-element tags, comments,
 * processing instructions, CDATA and DOCTYPE do not count; quoted attribute values may hold '>'. Reports
 * the line of the first start tag deeper than kMaxDepth. Malformed text is left to TinyXML. */
int depth_scan(Ctx &cx, const std::string &text) {
    int depth = 0, line = 1;
    const size_t n = text.size();
    auto skip_to = [&](size_t i, const char *end) {
        const size_t e = text.find(end, i);
        const size_t stop = e == std::string::npos ? n : e + strlen(end);
        for (size_t k = i; k < stop; k++) {
            line += text[k] == '\n';
        }
        return stop;
    };
    for (size_t i = 0; i < n;) {
        if (text[i] != '<') {
            line += text[i] == '\n';
            i++;
            continue;
        }
        if (text.compare(i, 4, "<!--") == 0) {
            i = skip_to(i, "-->");
        } else if (text.compare(i, 9, "<![CDATA[") == 0) {
            i = skip_to(i, "]]>");
        } else if (text.compare(i, 2, "<?") == 0) {
            i = skip_to(i, "?>");
        } else if (text.compare(i, 2, "<!") == 0) {
            i = skip_to(i, ">");
        } else {
            /* a tag: find its '>' outside quotes */
            const int tag_line = line;
            const bool end_tag = i + 1 < n && text[i + 1] == '/';
            char quote = 0;
            size_t k = i + 1;
            for (; k < n; k++) {
                const char c = text[k];
                line += c == '\n';
                if (quote) {
                    quote = c == quote ? 0 : quote;
                } else if (c == '"' || c == '\'') {
                    quote = c;
                } else if (c == '>') {
                    break;
                }
            }
            const bool empty_tag = k < n && k > i + 1 && text[k - 1] == '/';
            if (end_tag) {
                depth = depth > 0 ? depth - 1 : 0;
            } else if (!empty_tag && ++depth > kMaxDepth) {
                return cx.fail(MCA_EPARSE, "line %d: elements nested deeper than %d levels: not a URDF",
                               tag_line, kMaxDepth);
            }
            i = k < n ? k + 1 : n;
        }
    }
    return MCA_OK;
}

/* XML-level checks that urdfdom would only report without a line number. */
int prescan(Ctx &cx, const std::string &text) {
    TiXmlDocument doc;
    doc.Parse(text.c_str());
    if (doc.Error()) {
        if (doc.ErrorRow() > 0) {
            return cx.fail(MCA_EPARSE, "line %d, column %d: malformed XML: %s", doc.ErrorRow(),
                           doc.ErrorCol(), doc.ErrorDesc());
        }
        return cx.fail(MCA_EPARSE, "malformed XML: %s", doc.ErrorDesc());
    }
    const TiXmlElement *robot = doc.FirstChildElement("robot");
    if (!robot) {
        return cx.fail(MCA_EPARSE, "no <robot> element at the top level");
    }
    /* child link -> (parent link, joint); urdfdom builds a link that is its own parent, or a loop of
     * links, into shared_ptr cycles that it never frees (found by fuzz/fuzz_urdf): refused here */
    std::map<std::string, std::pair<std::string, std::string>> parent_of;
    for (const TiXmlElement *j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
        const char *name = j->Attribute("name");
        const char *type = j->Attribute("type");
        if (!name) {
            return cx.fail(MCA_EPARSE, "line %d: <joint> without a name", j->Row());
        }
        const TiXmlElement *pe = j->FirstChildElement("parent");
        const TiXmlElement *ce = j->FirstChildElement("child");
        const char *parent = pe ? pe->Attribute("link") : nullptr;
        const char *child = ce ? ce->Attribute("link") : nullptr;
        if (parent && child) {
            if (!strcmp(parent, child)) {
                return cx.fail(MCA_EPARSE, "line %d: joint '%s': link '%s' is its own parent", j->Row(), name,
                               child);
            }
            if (parent_of.count(child)) {
                return cx.fail(MCA_EPARSE, "line %d: joint '%s': link '%s' already has a parent (joint '%s')",
                               j->Row(), name, child, parent_of[child].second.c_str());
            }
            parent_of[child] = std::make_pair(std::string(parent), std::string(name));
        }
        cx.joint_line[name] = j->Row();
        if (!type) {
            return cx.fail(MCA_EPARSE, "line %d: joint '%s': no type attribute", j->Row(), name);
        }
        /* urdfdom rejects these without saying where; a side branch with them is rejected too */
        if ((!strcmp(type, "revolute") || !strcmp(type, "prismatic")) && !j->FirstChildElement("limit")) {
            return cx.fail(MCA_EPARSE, "line %d: joint '%s': %s joint has no <limit>", j->Row(), name, type);
        }
    }
    /* every link has at most one parent now: a walk up that takes more steps than there are joints is
     * going round a loop */
    for (const auto &e : parent_of) {
        std::string at = e.first;
        size_t steps = 0;
        for (auto it = parent_of.find(at); it != parent_of.end(); it = parent_of.find(at)) {
            at = it->second.first;
            if (++steps > parent_of.size()) {
                return cx.fail(MCA_EPARSE, "joint '%s': its links form a loop (a URDF is a tree)",
                               e.second.second.c_str());
            }
        }
    }
    return MCA_OK;
}

int load(Ctx &cx, mca_chain_t *chain, const char *tip_link) {
    /* File first, so that a missing file gets its own code and text. */
    FILE *f = fopen(cx.path, "rb");
    if (!f) {
        const int e = errno;
        return cx.fail(e == ENOENT || e == ENOTDIR ? MCA_ENOENT : MCA_EIO, "cannot open URDF file: %s",
                       strerror(e));
    }
    std::string text;
    char buf[4096];
    size_t got;
    const size_t max_size = 16u << 20; /* a URDF is kilobytes; this stops e.g. /dev/zero */
    while ((got = fread(buf, 1, sizeof(buf), f)) > 0 && text.size() <= max_size) {
        text.append(buf, got);
    }
    const bool read_failed = ferror(f) != 0;
    const int read_errno = errno;
    fclose(f);
    if (read_failed) {
        return cx.fail(MCA_EIO, "cannot read URDF file: %s",
                       read_errno ? strerror(read_errno) : "read error");
    }
    if (text.size() > max_size) {
        return cx.fail(MCA_EPARSE, "file is larger than %zu bytes: not a URDF", max_size);
    }

    int rc = utf8_check(cx, text);
    if (rc != MCA_OK) {
        return rc;
    }
    rc = depth_scan(cx, text);
    if (rc != MCA_OK) {
        return rc;
    }
    rc = prescan(cx, text);
    if (rc != MCA_OK) {
        return rc;
    }

    CaptureHandler cap;
    urdf::ModelInterfaceSharedPtr model;
    {
        CaptureScope scope(&cap);
        model = urdf::parseURDF(text);
    }
    if (!model) {
        return cx.fail(MCA_EPARSE, "not a valid URDF (urdfdom: %s)",
                       cap.text.empty() ? "no detail" : cap.text.c_str());
    }
    urdf::LinkConstSharedPtr root = model->getRoot();
    if (!root) {
        return cx.fail(MCA_EPARSE, "URDF has no root link");
    }

    /* Tip: named, or the single leaf of the tree. */
    urdf::LinkConstSharedPtr tip;
    if (tip_link) {
        tip = model->getLink(tip_link);
        if (!tip) {
            return cx.fail(MCA_ENOENT, "tip link '%s': no such <link>", tip_link);
        }
    } else {
        std::string leaves;
        int n_leaves = 0;
        for (const auto &kv : model->links_) {
            if (kv.second->child_links.empty()) {
                if (n_leaves++ < 4) {
                    leaves += (leaves.empty() ? "'" : ", '") + kv.first + "'";
                }
                tip = kv.second;
            }
        }
        if (n_leaves != 1) {
            return cx.fail(
                MCA_EPARSE,
                "the link tree branches into %d leaf links (%s%s): no single chain; name the tip link",
                n_leaves, leaves.c_str(), n_leaves > 4 ? ", ..." : "");
        }
    }

    /* Joints root -> tip (walk up from the tip; a tree has one such path). */
    std::vector<urdf::JointSharedPtr> path;
    std::vector<urdf::LinkConstSharedPtr> links; /* child link of each joint on the path */
    for (urdf::LinkConstSharedPtr l = tip; l && l->parent_joint; l = l->getParent()) {
        path.insert(path.begin(), l->parent_joint);
        links.insert(links.begin(), l);
        if (path.size() > 10000) {
            return cx.fail(MCA_EPARSE, "link '%s': parent loop", l->name.c_str());
        }
    }
    int dof = 0;
    for (const auto &j : path) {
        switch (j->type) {
        case urdf::Joint::REVOLUTE:
        case urdf::Joint::CONTINUOUS:
            dof++;
            break;
        case urdf::Joint::FIXED:
            break;
        default:
            return cx.fail(MCA_EPARSE, "%s: %s joint not supported (only revolute, continuous, fixed)",
                           cx.joint_ref(j->name).c_str(), type_name(j->type));
        }
    }
    if (dof > MCA_MAX_DOF) {
        return cx.fail(MCA_ERANGE, "chain '%s' -> '%s' has %d revolute joints, more than MCA_MAX_DOF (%d)",
                       root->name.c_str(), tip->name.c_str(), dof, MCA_MAX_DOF);
    }
    if (dof == 0) {
        return cx.fail(MCA_EPARSE, "chain '%s' -> '%s' has no revolute joint", root->name.c_str(),
                       tip->name.c_str());
    }

    std::unique_ptr<mca_chain_t> c(new mca_chain_t);
    memset(c.get(), 0, sizeof(*c));
    snprintf(c->name, sizeof(c->name), "%s", model->getName().c_str());
    snprintf(c->root_link, sizeof(c->root_link), "%s", root->name.c_str());
    snprintf(c->source, sizeof(c->source), "%s", cx.path);
    c->dof = dof;
    mca_pose_identity(&c->base);

    mca_pose_t acc; /* previous joint frame (or root) -> current link frame, fixed joints folded */
    mca_pose_identity(&acc);
    int k = 0;                             /* joints placed so far */
    c->link_radius[0] = link_radius(root); /* link 0 belongs to the root (and fixed children) */
    for (size_t i = 0; i < path.size(); i++) {
        const urdf::JointSharedPtr &j = path[i];
        mca_pose_t o;
        pose_from_urdf(&o, j->parent_to_joint_origin_transform);
        mca_pose_mul(&acc, &acc, &o);
        if (j->type != urdf::Joint::FIXED) {
            mca_joint_model_t *jm = &c->joint[k];
            const std::string ref = cx.joint_ref(j->name);
            if (j->name.size() >= sizeof(jm->name)) {
                return cx.fail(MCA_EPARSE, "%s: name longer than %zu characters", ref.c_str(),
                               sizeof(jm->name) - 1);
            }
            snprintf(jm->name, sizeof(jm->name), "%s", j->name.c_str());
            jm->origin = acc;
            const double ax = j->axis.x, ay = j->axis.y, az = j->axis.z;
            const double an = std::sqrt(ax * ax + ay * ay + az * az);
            if (!(an > 1e-9) || !std::isfinite(an)) {
                return cx.fail(MCA_EPARSE, "%s: <axis> is zero or not finite", ref.c_str());
            }
            jm->axis[0] = ax / an;
            jm->axis[1] = ay / an;
            jm->axis[2] = az / an;
            if (!j->limits) {
                return cx.fail(MCA_EPARSE, "%s: %s joint has no <limit> (its velocity limit is needed)",
                               ref.c_str(), type_name(j->type));
            }
            if (!(j->limits->velocity > 0.0 && j->limits->velocity <= MCA_JOINT_VEL_MAX)) {
                return cx.fail(MCA_EPARSE, "%s: <limit velocity> must be in (0, %g] rad/s (got %.15g)",
                               ref.c_str(), MCA_JOINT_VEL_MAX, j->limits->velocity);
            }
            jm->vel_limit = j->limits->velocity;
            if (j->type == urdf::Joint::CONTINUOUS) {
                jm->lower = -INFINITY;
                jm->upper = INFINITY;
                jm->continuous = 1;
            } else {
                const double lo = j->limits->lower, hi = j->limits->upper;
                if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) {
                    return cx.fail(MCA_EPARSE, "%s: <limit lower=%g upper=%g> is not a finite interval",
                                   ref.c_str(), lo, hi);
                }
                jm->lower = lo;
                jm->upper = hi;
                jm->continuous = 0;
            }
            mca_pose_identity(&acc);
            k++;
        }
        /* the child link (and later fixed children) belong to link k: point[k] -> point[k+1] */
        c->link_radius[k] = std::fmax(c->link_radius[k], link_radius(links[i]));
    }
    c->tool = acc;
    for (int l = 0; l <= dof; l++) {
        if (!std::isfinite(c->link_radius[l]) || c->link_radius[l] < 0.0) {
            return cx.fail(MCA_EPARSE, "collision radius of segment %d is negative or not finite", l);
        }
    }
    *chain = *c;
    if (cx.err && cx.errlen > 0) {
        cx.err[0] = '\0';
    }
    return MCA_OK;
}

} // namespace

extern "C" int mca_chain_load_urdf(mca_chain_t *chain, const char *path, const char *tip_link, char *err,
                                   size_t errlen) {
    Ctx cx{path ? path : "(null)", err, errlen, {}};
    if (!chain || !path) {
        return cx.fail(MCA_EINVAL, "NULL chain or path");
    }
    try {
        return load(cx, chain, tip_link);
    } catch (const std::bad_alloc &) {
        return cx.fail(MCA_ENOMEM, "out of memory");
    } catch (const std::exception &e) {
        return cx.fail(MCA_EPARSE, "not a valid URDF (%s)", e.what());
    } catch (...) {
        return cx.fail(MCA_EPARSE, "not a valid URDF (unknown exception)");
    }
}
