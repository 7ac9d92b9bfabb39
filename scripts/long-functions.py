#!/usr/bin/env python3
# Lists the non-test C/C++ functions longer than N lines (default 150), longest first: lines, file, first line,
# the end of the signature. Braces are matched on the tracked sources with comments and strings blanked; a
# heuristic, not a parser (a lambda inside a function counts with it). Run from the repository root:
#   scripts/long-functions.py [N]
import re, subprocess, sys
limit = int(sys.argv[1]) if len(sys.argv) > 1 else 150
files=subprocess.check_output(['git','ls-files','*.cpp','*.hpp','*.c','*.h']).decode().split()
out=[]
for f in files:
    if '/test/' in f or f.startswith('tests/') or '_test' in f: continue
    lines=open(f,errors='replace').read().split('\n')
    stack=[]
    for i,l in enumerate(lines):
        code=re.sub(r'//.*','',l)
        code=re.sub(r'"(\\.|[^"\\])*"','""',code)
        for ch_i,ch in enumerate(code):
            if ch=='{':
                infn=any(t[0]=='fn' for t in stack)
                ctx=' '.join(lines[max(0,i-2):i])+' '+code[:ch_i]
                if re.search(r'\b(namespace|struct|class|enum|union)\b[^;(]*$',ctx) or 'extern "C"' in ctx:
                    stack.append(('ns',i,''))
                elif not infn and re.search(r'\)\s*(const)?\s*(noexcept)?\s*(override)?\s*(->\s*[\w:<>,\s]+)?\s*(:.*)?$',ctx.strip()):
                    stack.append(('fn',i,ctx.strip()[-90:]))
                else:
                    stack.append(('blk',i,''))
            elif ch=='}' and stack:
                t=stack.pop()
                if t[0]=='fn' and i-t[1]+1>limit: out.append((i-t[1]+1,f,t[1]+1,t[2]))
for n,f,s,name in sorted(out,reverse=True): print(n,f,s,name[-70:])
