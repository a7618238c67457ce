// MiniJson.cs - a strict JSON reader (RFC 8259) for the roster manifest: objects keep their key
// order (a roster's states and types are listed in the order the catalog wrote them), numbers are
// doubles. Unity's JsonUtility reads no dictionaries and .NET's readers are not in every Unity
// profile, so the package carries this one (under 200 lines).
using System;
using System.Collections.Generic;
using System.Globalization;
using System.Text;

namespace Crowdbake
{
    // A JSON object: its members in file order.
    public sealed class JsonObject
    {
        public readonly List<string> Keys = new List<string>();
        readonly Dictionary<string, object> values = new Dictionary<string, object>(StringComparer.Ordinal);

        public bool Has(string key) { return values.ContainsKey(key); }
        public object Get(string key)
        {
            object v;
            return values.TryGetValue(key, out v) ? v : null;
        }
        internal bool Add(string key, object value)
        {
            if (values.ContainsKey(key)) return false;
            Keys.Add(key);
            values[key] = value;
            return true;
        }
    }

    public sealed class JsonException : Exception
    {
        public JsonException(string message) : base(message) { }
    }

    // Values: JsonObject, List<object>, string, double, bool, or null.
    public sealed class MiniJson
    {
        readonly string text;
        int at;
        const int MaxDepth = 64; // a hostile file must not choose the stack's depth

        MiniJson(string text) { this.text = text; }

        public static object Parse(string text)
        {
            var p = new MiniJson(text);
            object v = p.Value(0);
            p.Space();
            if (p.at != text.Length) throw p.Error("unexpected text after the value");
            return v;
        }

        JsonException Error(string what)
        {
            int line = 1, column = 1;
            for (int i = 0; i < at && i < text.Length; ++i) {
                if (text[i] == '\n') { ++line; column = 1; } else ++column;
            }
            return new JsonException("line " + line + ", column " + column + ": " + what);
        }

        void Space()
        {
            while (at < text.Length && (text[at] == ' ' || text[at] == '\t' || text[at] == '\n' || text[at] == '\r')) ++at;
        }

        void Expect(string word)
        {
            if (string.CompareOrdinal(text, at, word, 0, word.Length) != 0) throw Error("expected " + word);
            at += word.Length;
        }

        object Value(int depth)
        {
            if (depth > MaxDepth) throw Error("nested deeper than " + MaxDepth);
            Space();
            if (at >= text.Length) throw Error("unexpected end of the text");
            char c = text[at];
            if (c == '{') return Object(depth);
            if (c == '[') return Array(depth);
            if (c == '"') return String();
            if (c == 't') { Expect("true"); return true; }
            if (c == 'f') { Expect("false"); return false; }
            if (c == 'n') { Expect("null"); return null; }
            return Number();
        }

        JsonObject Object(int depth)
        {
            var o = new JsonObject();
            ++at;
            Space();
            if (at < text.Length && text[at] == '}') { ++at; return o; }
            for (;;) {
                Space();
                if (at >= text.Length || text[at] != '"') throw Error("expected a member name in quotes");
                string key = String();
                Space();
                Expect(":");
                if (!o.Add(key, Value(depth + 1))) throw Error("member \"" + key + "\" appears twice");
                Space();
                if (at < text.Length && text[at] == ',') { ++at; continue; }
                Expect("}");
                return o;
            }
        }

        List<object> Array(int depth)
        {
            var a = new List<object>();
            ++at;
            Space();
            if (at < text.Length && text[at] == ']') { ++at; return a; }
            for (;;) {
                a.Add(Value(depth + 1));
                Space();
                if (at < text.Length && text[at] == ',') { ++at; continue; }
                Expect("]");
                return a;
            }
        }

        string String()
        {
            var s = new StringBuilder();
            ++at;
            while (at < text.Length) {
                char c = text[at++];
                if (c == '"') return s.ToString();
                if (c < 0x20) throw Error("control character in a string");
                if (c != '\\') { s.Append(c); continue; }
                if (at >= text.Length) break;
                char e = text[at++];
                switch (e) {
                case '"': case '\\': case '/': s.Append(e); break;
                case 'b': s.Append('\b'); break;
                case 'f': s.Append('\f'); break;
                case 'n': s.Append('\n'); break;
                case 'r': s.Append('\r'); break;
                case 't': s.Append('\t'); break;
                case 'u':
                    int code;
                    if (at + 4 > text.Length ||
                        !int.TryParse(text.Substring(at, 4), NumberStyles.AllowHexSpecifier, CultureInfo.InvariantCulture, out code))
                        throw Error("bad \\u escape");
                    s.Append((char)code);
                    at += 4;
                    break;
                default: throw Error("bad escape \\" + e);
                }
            }
            throw Error("unterminated string");
        }

        static bool IsDigit(char c) { return c >= '0' && c <= '9'; } // ASCII only, as JSON

        double Number()
        {
            int start = at;
            if (at < text.Length && text[at] == '-') ++at;
            int digits = at;
            while (at < text.Length && IsDigit(text[at])) ++at;
            if (at == digits || (text[digits] == '0' && at - digits > 1)) throw Error("expected a value");
            if (at < text.Length && text[at] == '.') {
                int frac = ++at;
                while (at < text.Length && IsDigit(text[at])) ++at;
                if (at == frac) throw Error("expected digits after the decimal point");
            }
            if (at < text.Length && (text[at] == 'e' || text[at] == 'E')) {
                ++at;
                if (at < text.Length && (text[at] == '+' || text[at] == '-')) ++at;
                int exp = at;
                while (at < text.Length && IsDigit(text[at])) ++at;
                if (at == exp) throw Error("expected digits in the exponent");
            }
            return double.Parse(text.Substring(start, at - start), NumberStyles.Float, CultureInfo.InvariantCulture);
        }
    }
}
