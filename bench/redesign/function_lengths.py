#!/usr/bin/python3
"""The longest function definitions of C++ sources, for the redesign's "no function over a
screen" check (issue 42). A heuristic by brace matching, not a parser: a definition is a line
ending in '{' whose header (back to where its parentheses open) names a function and is
indented at most 4 spaces (namespace-level functions and members of a class body); its length
runs to the matching '}'. Lambdas, control statements, structs and classes are not counted.

    bench/redesign/function_lengths.py ROOT DIR [DIR ...]     # TOP=N rows (default 8)
    -> "LINES FILE FIRST_LINE NAME", longest first
"""
import os
import re
import sys
root=sys.argv[1]; dirs=sys.argv[2:]
ctrl={'if','for','while','switch','catch','return','sizeof','decltype','static_assert','alignof','requires'}
def strip(s): return re.sub(r'"(\\.|[^"\\])*"|\'(\\.|[^\'\\])*\'|//.*','',s)
res=[]
for d in dirs:
    for dp,_,fs in os.walk(os.path.join(root,d)):
        for f in fs:
            if not f.endswith(('.cpp','.hpp')): continue
            p=os.path.join(dp,f); L=[strip(x) for x in open(p,errors='replace').read().split('\n')]
            i=0
            while i<len(L):
                line=L[i].rstrip()
                if line.endswith('{') and ')' in ' '.join(L[max(0,i-8):i+1]):
                    # find the header start: walk back until parens balance
                    k=i; bal=0; txt=''
                    while k>=0:
                        txt=L[k]+' '+txt
                        bal=txt.count('(')-txt.count(')')
                        if bal==0 and '(' in txt: break
                        k-=1
                    first=L[k] if k>=0 else ''
                    m=re.match(r'^(\s*)(.*?)([~\w:]+(?:<[^()]*>)?)\s*\(',first)
                    hdr=txt
                    ok = m and 'return' not in first and 'struct ' not in L[i] and 'class ' not in L[i] and m.group(3).split('::')[-1] not in ctrl and not re.match(r'\s*(else|do|namespace|struct|class|enum)\b',first) \
                         and re.search(r'\)\s*(const|override|noexcept|final|mutable|->\s*[\w:<>&* ]+|\s)*(:.*)?\{\s*$',hdr) \
                         and '=' not in m.group(2) and not re.search(r'\[[^\]]*\]\s*\(',hdr) and m.group(2).strip()!='' or (m and len(m.group(1))==0 and m.group(3)[0]!='~' and '::' in m.group(3))
                    if ok and len(m.group(1))<=4:
                        depth=0; j=i
                        while j<len(L):
                            depth+=L[j].count('{')-L[j].count('}')
                            if depth<=0: break
                            j+=1
                        res.append((j-k+1,p[len(root)+1:],k+1,m.group(3)))
                        i=j+1; continue
                i+=1
res.sort(reverse=True)
for r in res[:int(os.environ.get('TOP','8'))]: print(*r)
